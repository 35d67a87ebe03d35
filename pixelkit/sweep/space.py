"""Sweep axes: design parameters, stimuli and simulator options, parsed and validated.

An axis is written ``NAME=VALUES``:

- ``NAME``: a design-file key in dotted form (``pixel.sf_bias``, ``primary.t_int``,
  ``temperature``, ``corner``, ``afe.c13`` ...), a stimulus (``iph_p``, ``iph_s`` in A,
  ``t_exp`` in s) or a simulator option ``option.<name>`` (``option.reltol``);
- ``VALUES``: a comma list (``300nA,400nA,500nA``; design values keep their units and
  are checked by the design schema exactly as in a file), ``lin:START:STOP:N`` or
  ``log:START:STOP:N`` (numbers with units: ``log:10p:1n:5``).

Every design point is re-loaded through the design loader, so a value outside what the
schema allows is a ConfigError naming the field, before anything runs.
"""
from __future__ import annotations

import copy
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ConfigError

STIMULI = {"iph_p": "A", "iph_s": "A", "t_exp": "s"}
_NAME = re.compile(r"^(option\.[a-z]{1,16}|[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*)$")
_SI = {"f": 1e-15, "p": 1e-12, "n": 1e-9, "u": 1e-6, "m": 1e-3, "k": 1e3, "M": 1e6, "G": 1e9}


@dataclass(frozen=True)
class Axis:
    name: str
    values: tuple      # what goes in: numbers (stimuli, options) or design-file values

    @property
    def kind(self) -> str:
        if self.name in STIMULI:
            return "stimulus"
        return "option" if self.name.startswith("option.") else "design"

    @property
    def column(self) -> str:
        """Name of the axis in tables: with the SI unit of a stimulus (``iph_p_A``)."""
        return f"{self.name}_{STIMULI[self.name]}" if self.kind == "stimulus" else self.name


def number(text: str, what: str) -> float:
    """``1.5n``, ``1.5e-9``, ``1.5 nA`` -> 1.5e-9 (the unit letters after the prefix are ignored)."""
    m = re.match(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([fpnumkMG]?)[A-Za-z/]*\s*$", text)
    if not m:
        raise ConfigError("sweep", what, text, "a number, optionally with an SI prefix (10p, 1.5n, 2e-9)")
    return float(m.group(1)) * _SI.get(m.group(2), 1.0)


def parse_axis(spec: str) -> Axis:
    if "=" not in spec:
        raise ConfigError("sweep", "--over", spec, "NAME=VALUES, e.g. pixel.sf_bias=300nA,400nA")
    name, _, vals = spec.partition("=")
    name = name.strip()
    if not _NAME.match(name):
        raise ConfigError("sweep", "--over", name, "a dotted design key, iph_p, iph_s, t_exp or option.<name>")
    numeric = name in STIMULI or name.startswith("option.")
    vals = vals.strip()
    if vals.startswith(("lin:", "log:")):
        parts = vals.split(":")
        if len(parts) != 4 or not parts[3].isdigit() or not 1 <= int(parts[3]) <= 10000:
            raise ConfigError("sweep", name, vals, "lin:START:STOP:N or log:START:STOP:N with 1 <= N <= 10000")
        a, b = number(parts[1], name), number(parts[2], name)
        if parts[0] == "log" and (a <= 0 or b <= 0):
            raise ConfigError("sweep", name, vals, "log ranges of positive numbers")
        grid = np.linspace(a, b, int(parts[3])) if parts[0] == "lin" else np.geomspace(a, b, int(parts[3]))
        values = tuple(float(x) for x in grid)
    else:
        items = [v.strip() for v in vals.split(",") if v.strip()]
        if not items:
            raise ConfigError("sweep", name, vals, "at least one value")
        values = tuple(number(v, name) for v in items) if numeric else tuple(_design_value(v) for v in items)
    if name in STIMULI and any(v < 0 or (name == "t_exp" and v <= 0) for v in values):
        raise ConfigError("sweep", name, values, "currents >= 0 A and exposures > 0 s")
    return Axis(name, values)


def _design_value(text: str):
    """A design-file value as TOML would hold it: true / false, a number if it is one, else the text."""
    if text in ("true", "false"):
        return text == "true"
    try:
        return float(text) if re.match(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$", text) else text
    except ValueError:
        return text


def design_with(design, overrides: dict):
    """``design`` with dotted-key ``overrides`` applied to its file content (None: the key left out),
    re-validated."""
    if not overrides:
        return design
    from ..design import load_design
    from ..fileio import write_atomic
    from ..schema import to_toml
    raw = copy.deepcopy(design.raw)
    base = Path(design.source).resolve().parent
    tech = raw.get("technology", "")
    if isinstance(tech, str) and tech.endswith(".toml") and not Path(tech).is_absolute():
        raw["technology"] = str(base / tech)
    if isinstance(raw.get("layout"), dict) and not Path(raw["layout"].get("gds", "/")).is_absolute():
        raw["layout"]["gds"] = str(base / raw["layout"]["gds"])
    for key, value in overrides.items():
        node, *path = key.split(".")
        parts = [node, *path]
        cur = raw
        for p in parts[:-1]:
            if not isinstance(cur.get(p, {}), dict):
                raise ConfigError(design.source, key, value, "a key inside a design table")
            cur = cur.setdefault(p, {})
        if value is None:    # a key left out (close: a knob a circuit choice does not have)
            cur.pop(parts[-1], None)
        else:
            cur[parts[-1]] = value
    if hasattr(design, "reloaded"):   # a pixel read by role: its family's loader, at its own path (its netlist
        # and technology resolve as in the file)
        try:
            return design.reloaded(raw)
        except ConfigError as exc:
            raise ConfigError(f"{design.source} (sweep point {overrides})", exc.field, exc.value,
                              exc.allowed) from None
    with tempfile.TemporaryDirectory(prefix="pixelkit-sweep-") as tmp:
        path = Path(tmp) / f"{design.name}.toml"
        write_atomic(path, to_toml(raw))
        try:
            d = load_design(path)
        except ConfigError as exc:  # name the user's design and the swept value, not the temp file
            raise ConfigError(f"{design.source} (sweep point {overrides})", exc.field, exc.value,
                              exc.allowed) from None
    from dataclasses import replace
    return replace(d, source=design.source)


def si_value(design, key: str):
    """(value in SI, unit) of the design field ``key`` when it is a quantity, else None."""
    import dataclasses
    obj, fields_ = design, None
    for part in key.split("."):
        if not dataclasses.is_dataclass(obj):
            return None
        fields_ = {f.name: f for f in dataclasses.fields(obj)}
        if part not in fields_:
            return None
        f, obj = fields_[part], getattr(obj, part)
    if f.metadata.get("kind") != "qty" or not isinstance(obj, (int, float)):
        return None
    dim = f.metadata.get("dim", "1")
    return float(obj), ("" if dim == "1" else dim.replace("/", "_per_"))
