"""The MIM capacitors' process corners, read from the model library.

A foundry library gives the MIM capacitor its own corner sections (GF180MCU's
``sm141064.ngspice``: ``mimcap_typical`` / ``mimcap_ff`` / ``mimcap_ss``), each setting
the factor the capacitor's model multiplies its area and perimeter capacitance by
(``.param mim_corner_2p0fF=1.1``; the subcircuit ``cap_mim_2f0fF`` has
``c_cox='1.99e-3*mim_corner_2p0fF'``). The kit's readout capacitors are ideal capacitors of
the design's values, so a corner's factor scales them (``verify.conditions``); the
section itself is never included in a deck (GF180's pulls in a file the open library
does not ship). The technology's ``[models.mim_corners]`` table names the section per
process corner; a corner it does not name keeps the typical value (factor 1).
"""
from __future__ import annotations

import re
from functools import lru_cache

from ..errors import ConfigError
from ..readfile import FileRefused, read_bytes

_PARAM = re.compile(r"^[ \t]*\.param[ \t]+([A-Za-z_]\w*)[ \t]*=[ \t]*'?([-+0-9.eE]+)'?[ \t]*$", re.I | re.M)


@lru_cache(maxsize=64)
def _text(path: str) -> str:
    return read_bytes(path, "model file", "model").decode("latin-1")


def _block(text: str, start: re.Pattern, end: re.Pattern) -> str | None:
    m = start.search(text)
    if m is None:
        return None
    e = end.search(text, m.end())
    return text[m.end(): e.start() if e else len(text)]


def corner_factor(include, mim_model: str, source: str, where: str) -> float:
    """The factor the library's section ``include`` sets on ``mim_model``'s capacitance."""
    try:
        text = _text(str(include.file))
    except FileRefused as exc:
        raise ConfigError(source, where, include.name, f"a readable model file ({exc.value})") from None
    section = _block(text, re.compile(rf"^[ \t]*\.lib[ \t]+{re.escape(include.section)}[ \t]*$", re.I | re.M),
                     re.compile(r"^[ \t]*\.endl\b", re.I | re.M))
    if section is None:
        raise ConfigError(source, where, include.section, f"a section of {include.name} (.LIB {include.section})")
    body = _block(text, re.compile(rf"^[ \t]*\.subckt[ \t]+{re.escape(mim_model)}\b.*$", re.I | re.M),
                  re.compile(r"^[ \t]*\.ends\b", re.I | re.M))
    if body is None:
        raise ConfigError(source, "passives.mim_model", mim_model, f"a subcircuit of {include.name}")
    cox = re.search(r"\bc_cox\s*=\s*'([^']*)'", body, re.I)
    used = set(re.findall(r"[A-Za-z_]\w*", cox.group(1))) if cox else set()
    found = {k.lower(): float(v) for k, v in _PARAM.findall(section) if k in used}
    if len(found) != 1:
        raise ConfigError(source, where, include.section,
                          f"a section setting the one parameter {mim_model}'s c_cox is scaled by "
                          f"({', '.join(sorted(used)) or 'none found'})")
    factor = next(iter(found.values()))
    if not 0.5 <= factor <= 2.0:
        raise ConfigError(source, where, f"{include.section}: {factor:g}", "a capacitance factor between 0.5 and 2")
    return factor


def mim_factors(tech, source: str) -> dict:
    """Process corner -> the factor on the MIM capacitors (only the corners the table names)."""
    named = tech.models.mim
    if named and tech.passives is None:
        raise ConfigError(source, "models.mim_corners", sorted(named),
                          "a [passives] table naming the MIM model (mim_model) the corners scale")
    return {c: corner_factor(inc, tech.passives.mim_model, source, f"models.mim_corners.{c}")
            for c, inc in named.items()}
