"""Physical quantities as they are written in design and technology files.

A value is a string ``"<number> <unit>"`` (``"15.1 um"``, ``"26.54 fF"``,
``"0.64 um2"``, ``"1.17 uW/um2"``, ``"27 degC"``). It is converted to SI once,
here, and checked against the dimension the field expects, so that a length
written in farads, or a length with no unit at all, is refused with a message
that names the field.
"""
from __future__ import annotations

import math
import re

from .errors import ConfigError

# Dimension vectors over (m, s, kg, A, K, cd): only what the kit uses.
_BASE = {
    "m": (1, 0, 0, 0, 0, 0),
    "s": (0, 1, 0, 0, 0, 0),
    "g": (0, 0, 1, 0, 0, 0),
    "A": (0, 0, 0, 1, 0, 0),
    "K": (0, 0, 0, 0, 1, 0),
    "cd": (0, 0, 0, 0, 0, 1),
}
_DERIVED = {
    # symbol: (scale to SI, dimension)
    "Hz": (1.0, (0, -1, 0, 0, 0, 0)),
    "V": (1.0, (2, -3, 1, -1, 0, 0)),
    "F": (1.0, (-2, 4, -1, 2, 0, 0)),
    "W": (1.0, (2, -3, 1, 0, 0, 0)),
    "C": (1.0, (0, 1, 0, 1, 0, 0)),
    "S": (1.0, (-2, 3, -1, 2, 0, 0)),
    "Ohm": (1.0, (2, -3, 1, -2, 0, 0)),
    "lx": (1.0, (-2, 0, 0, 0, 0, 1)),
    "e": (1.602176634e-19, (0, 1, 0, 1, 0, 0)),  # electrons, as a charge
    "deg": (math.pi / 180.0, (0, 0, 0, 0, 0, 0)),
    "rad": (1.0, (0, 0, 0, 0, 0, 0)),
    "dB": (None, (0, 0, 0, 0, 0, 0)),  # handled specially
    "%": (0.01, (0, 0, 0, 0, 0, 0)),
}
_PREFIX = {"f": 1e-15, "p": 1e-12, "n": 1e-9, "u": 1e-6, "µ": 1e-6, "m": 1e-3,
           "c": 1e-2, "k": 1e3, "M": 1e6, "G": 1e9}

#: Names of the dimensions a field may ask for, with an example for messages.
DIMENSIONS = {
    "1": ((0, 0, 0, 0, 0, 0), "0.5"),
    "m": ((1, 0, 0, 0, 0, 0), "15.1 um"),
    "m2": ((2, 0, 0, 0, 0, 0), "0.64 um2"),
    "s": ((0, 1, 0, 0, 0, 0), "1 ms"),
    "Hz": ((0, -1, 0, 0, 0, 0), "500 kHz"),
    "V": ((2, -3, 1, -1, 0, 0), "3.3 V"),
    "A": ((0, 0, 0, 1, 0, 0), "400 nA"),
    "F": ((-2, 4, -1, 2, 0, 0), "26.54 fF"),
    "F/m2": ((-4, 4, -1, 2, 0, 0), "0.1 fF/um2"),
    "F/m": ((-3, 4, -1, 2, 0, 0), "0.3 fF/um"),
    "A/m2": ((-2, 0, 0, 1, 0, 0), "1 nA/cm2"),
    "A/m": ((-1, 0, 0, 1, 0, 0), "1 fA/um"),
    "W/m2": ((0, -3, 1, 0, 0, 0), "1.17 uW/um2"),
    "A/W": ((-2, 3, -1, 1, 0, 0), "0.3 A/W"),
    "K": ((0, 0, 0, 0, 1, 0), "27 degC"),
    "Ohm": ((2, -3, 1, -2, 0, 0), "25 kOhm"),
    "V2*F": ((2, -2, 1, 0, 0, 0), "6.9e-25 V2*F"),
    "lx": ((-2, 0, 0, 0, 0, 1), "1000 lx"),
    "m/s": ((1, -1, 0, 0, 0, 0), "60 km/h"),
    "m2/s": ((2, -1, 0, 0, 0, 0), "35 cm2/s"),
    "rad": ((0, 0, 0, 0, 0, 0), "7.4 deg"),
    "C": ((0, 1, 0, 1, 0, 0), "20000 e-"),
    "V/C": ((2, -4, 1, -2, 0, 0), "11 uV/e-"),
    "W": ((2, -3, 1, 0, 0, 0), "10 mW"),
    "V*m": ((3, -3, 1, -1, 0, 0), "5 mV*um"),
}

_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_QTY = re.compile(rf"^\s*({_NUMBER})\s*(.*?)\s*$")
_ELECTRON = re.compile(r"(?<![A-Za-z])([kM]?)e-(?=$|/|\*)")
_TERM = re.compile(r"^([A-Za-zµ%]+)(?:\^?(-?\d))?$")


def _symbol(sym: str) -> tuple[float, tuple[int, ...]]:
    """Scale and dimension of one symbol, prefix allowed (``um``, ``kHz``, ``fF``)."""
    if sym == "h":
        return 3600.0, _BASE["s"]
    if sym == "min":
        return 60.0, _BASE["s"]
    if sym == "dB":
        raise ValueError("dB is a ratio, only for dimensionless fields")
    for table in (_DERIVED, _BASE):
        if sym in table:
            if table is _BASE:
                return (1e-3 if sym == "g" else 1.0), table[sym]
            return table[sym]
    if len(sym) > 1 and sym[0] in _PREFIX:
        rest = sym[1:]
        if rest in _BASE:
            scale = _PREFIX[sym[0]] * (1e-3 if rest == "g" else 1.0)
            return scale, _BASE[rest]
        if rest in _DERIVED and _DERIVED[rest][0] is not None and rest not in ("%", "deg", "e"):
            return _PREFIX[sym[0]] * _DERIVED[rest][0], _DERIVED[rest][1]
        if rest == "e" and sym[0] in "kM":  # ke-, Me- (electrons); "me" and "ue" mean nothing
            return _PREFIX[sym[0]] * _DERIVED["e"][0], _DERIVED["e"][1]
    raise ValueError(f"unknown unit symbol {sym!r}")


def parse_unit(text: str) -> tuple[float, tuple[int, ...]]:
    """Scale to SI and dimension of a unit such as ``fF/um2`` or ``km/h``."""
    text = text.replace("²", "2").replace("·", "*")
    text = _ELECTRON.sub(r"\1e", text)  # "e-" (electrons, as designers write it) is "e"
    scale, dim = 1.0, [0] * 6
    parts = re.split(r"(/|\*)", text)
    sign = 1
    for part in parts:
        if part == "/":
            sign = -1
            continue
        if part == "*":
            continue
        m = _TERM.match(part.strip())
        if not m:
            raise ValueError(f"cannot read unit {text!r}")
        s, d = _symbol(m.group(1))
        power = int(m.group(2) or 1) * sign
        scale *= s ** power
        dim = [a + b * power for a, b in zip(dim, d)]
    return scale, tuple(dim)


def quantity(value, dimension: str, field: str, source: str = "") -> float:
    """Convert a file value to SI, checking it has the dimension ``dimension``.

    Dimensionless fields accept plain numbers. Every other field needs a unit.
    Temperatures accept ``degC`` (converted to kelvin) and ``K``.
    """
    want, example = DIMENSIONS[dimension]
    if isinstance(value, bool):
        raise ConfigError(source, field, value, f"a quantity like '{example}'")
    if isinstance(value, (int, float)):
        if dimension == "1":
            return _finite(float(value), field, source, example, value)
        raise ConfigError(source, field, value, f"a number with a unit, like '{example}'")
    if not isinstance(value, str):
        raise ConfigError(source, field, value, f"a quantity like '{example}'")
    m = _QTY.match(value)
    if not m:
        raise ConfigError(source, field, value, f"a number with a unit, like '{example}'")
    number, unit = float(m.group(1)), m.group(2)
    if dimension == "K" and unit in ("degC", "°C", "C"):
        return _finite(number + 273.15, field, source, example, value)
    if unit == "dB" and dimension == "1":
        try:
            return _finite(10 ** (number / 20.0), field, source, example, value)
        except OverflowError:
            raise ConfigError(source, field, value, f"a finite value, like '{example}'") from None
    if unit == "" and dimension != "1":
        raise ConfigError(source, field, value, f"a number with a unit, like '{example}'")
    try:
        scale, dim = parse_unit(unit) if unit else (1.0, (0,) * 6)
    except ValueError:
        raise ConfigError(source, field, value,
                          f"a known unit of {dimension}, like '{example}'") from None
    if dim != want:
        raise ConfigError(source, field, value,
                          f"a quantity in {dimension}, like '{example}' (the unit '{unit}' is not)")
    return _finite(number * scale, field, source, example, value)


def _finite(x: float, field: str, source: str, example: str, shown) -> float:
    if not math.isfinite(x):
        raise ConfigError(source, field, shown, f"a finite value, like '{example}'")
    return x


_SI_PREFIX = [(1e9, "G"), (1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"), (1e-6, "u"), (1e-9, "n"),
              (1e-12, "p"), (1e-15, "f"), (1e-18, "a")]
_PREFIXED = {"m": "m", "s": "s", "Hz": "Hz", "V": "V", "A": "A", "F": "F", "m2": "m2", "Ohm": "Ohm", "W": "W"}


def si_text(x: float, dimension: str, digits: int = 6) -> str:
    """``x`` (SI, of ``dimension``) as a user would write it: ``"50 mV"``, ``"10 nF"``, ``"-60 degC"``
    (``digits`` significant digits)."""
    g = f".{digits}g"
    if dimension == "K":  # below 150 K only differences occur (a doubling step): no offset
        return f"{x - 273.15:{g}} degC" if x >= 150 else f"{x:{g}} K"
    if dimension == "m2" and x != 0:
        return f"{x * 1e12:{g}} um2"
    if dimension in _PREFIXED and x != 0:
        for scale, p in _SI_PREFIX:
            if abs(x) >= scale * 0.9999999:
                return f"{x / scale:{g}} {p}{_PREFIXED[dimension]}"
        return f"{x / 1e-18:{g}} a{_PREFIXED[dimension]}"
    return f"{x:{g}}" if dimension in ("1", "") else f"{x:{g}} {dimension}"
