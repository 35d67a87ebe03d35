"""The ``[close]`` table of a design file: the knobs ``pixelkit close`` may move, their bounds,
the objective; validated when the file loads, like every other table.

::

    [close]
    objective = "min power"          # or "max full_well_primary", "min area", "min pixel.sf_bias"

    [close.knobs]
    "pixel.v_fd_reset" = ["1.6 V", "2.2 V"]
    "pixel.sf_bias" = { min = "600 nA", max = "1.5 uA", scale = "log" }
    "pixel.devices.rst_w" = { min = "0.42 um", max = "2 um", step = "5 nm" }

A knob is any numeric (continuous) key of the design file, or a circuit choice (a key that names
one of a few circuits, ``"pixel.gate_drive" = { choices = ["supply", "boosted"] }``): close then
solves the numeric knobs for each combination of choices and keeps the best. A numeric knob the
design leaves absent starts at the middle of its bounds (and is left out under a choice with which
the design file refuses it, as ``pixel.v_gate`` with ``gate_drive = "supply"``). Refused when the file loads, each
naming the field (exit 2): a key the design file does not have, a whole number (``rows``), a
text or a flag; a key the sign-off itself fixes (``temperature``: every condition of the grid
sets it; ``[verify]``, ``[spec]``, ``[experiment]``: they say how the specs' figures are
measured, so moving them moves the measurement, not the chip); a key no spec can depend on
(``[scene]``, ``[optics]``, ``[sizing]``: ``pixelkit verify`` does not read them); a bound
that is missing, not a quantity of the key's unit, infinite, outside what the design file
accepts for that key, or a ``min`` not below its ``max``; a ``log`` scale with a bound <= 0;
a ``step`` that is not below the span or below 1e-9 of it. A knob no spec depends on through the
simulations (every spec's figure unchanged when it moves) is refused by ``pixelkit close`` at
its first sensitivity step, with the same exit status (``close.model``).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

from ..errors import ConfigError
from ..schema import check_range, integer, items, limit, named, num, text
from ..units import DIMENSIONS, quantity

#: Tables whose keys are not knobs, and why (the message of the refusal).
FIXED = {
    "spec": "a key of a spec: the specs are what close must meet, not what it may change",
    "verify": "a key of the sign-off grid ([verify]), which the specs are checked over",
    "close": "a key of the [close] table itself",
    "experiment": "a key that says how the specs' figures are measured ([experiment]): moving it moves "
                  "the measurement, not the chip",
    "temperature": "fixed by the sign-off grid: every condition of [verify] temperatures (or a spec's "
                   "own) sets the die temperature",
    "corner": "fixed by the sign-off grid: every condition sets the process corner",
}
#: Tables no measurement of ``pixelkit verify`` reads: a knob there moves no spec.
UNREAD = ("scene", "optics", "sizing", "layout")
#: At most this many knobs (the benchmark measures 2, 5 and 10).
MAX_KNOBS = 32
#: At most this many combinations of circuit choices (close solves each).
MAX_COMBINATIONS = 8
#: Objectives that are not a figure's name.
OBJECTIVES = {"power": "power_chip", "area": "area"}


@dataclass(frozen=True)
class Knob:
    """One knob (``[close.knobs]``, keyed by the design key it frees): its bounds, scale and step."""
    min: object = limit(doc="lower bound (\"1.6 V\")", of="design key")
    max: object = limit(doc="upper bound (\"2.2 V\")", of="design key")
    scale: str = text("auto", choices=("auto", "lin", "log"),
                      doc="how close steps it: lin (in % of the span), log (in % of the value); auto: log when "
                          "min > 0 and max >= 3 x min, else lin")
    step: object = limit(of="design key", doc="grid the written value is rounded to (\"5 nm\"): every candidate is "
                                              "simulated as rounded (absent: 6 significant digits)")
    choices: tuple = items(text(), (), min_len=1, max_len=8,
                           doc="a circuit choice instead of bounds: the values of a key that names one "
                               "(\"pixel.gate_drive\" = { choices = [\"supply\", \"boosted\"] }): close solves the "
                               "numeric knobs for each and keeps the best; one value: the circuit the revision uses "
                               "(\"afe.opamp\" = { choices = [\"ota\"] }), chosen by the designer, not by close")
    tied: tuple = items(text(), (), min_len=1, max_len=8,
                        doc="design keys set to this knob's value too, one knob for both (\"afe.c11\" = { min = "
                            "\"150 fF\", max = \"600 fF\", tied = [\"afe.c13\"] }: C13 = C11, the AFE's gain "
                            "C11 / C13 stays 1 while its capacitors move)")
    name: str = field(default="", metadata=dict(kind="skip"))
    lo: float = field(default=0.0, metadata=dict(kind="skip"))
    hi: float = field(default=0.0, metadata=dict(kind="skip"))
    grid: float | None = field(default=None, metadata=dict(kind="skip"))
    dim: str = field(default="1", metadata=dict(kind="skip"))
    unit_required: bool = field(default=False, metadata=dict(kind="skip"))

    @property
    def log(self) -> bool:
        return self.scale == "log" or (self.scale == "auto" and self.lo > 0 and self.hi >= 3 * self.lo)

    def validate(self, path, source, raw):
        if self.choices:
            for key in ("min", "max", "step", "tied"):
                if key in raw:
                    raise ConfigError(source, f"{path}.{key}", raw[key], "no bounds on a knob with choices "
                                      "(a circuit choice takes one of its values)")
            return
        for bound in ("min", "max"):
            if getattr(self, bound) is None:
                raise ConfigError(source, f"{path}.{bound}", None, "a bound with the unit of the design key "
                                  "(both min and max), or choices")


@dataclass(frozen=True)
class CloseSettings:
    """What ``pixelkit close`` may change and what it optimises (docs/close.md)."""
    knobs: tuple = named(Knob, keys="dotted", pair=("min", "max"),
                         doc="the design keys close may move, each with its bounds: "
                             "\"pixel.sf_bias\" = [\"600 nA\", \"1.5 uA\"] or a table with min, max, scale, step")
    objective: str = text("min power", doc="\"min X\" or \"max X\": X is power (the chip's, at the nominal "
                                           "condition), area (gate area of the pixel's transistors), a figure "
                                           "a spec can name (at the nominal condition) or one of the knobs")
    margin: float = num(0.0, ge=0.0, le=0.5, doc="margin every spec must keep at every condition, in % of its "
                                                 "limit (\"2 %\"): a guard band against the simulator's scatter")
    tolerance: float = num(0.01, gt=0.0, le=0.2, plausible=(1e-6, 0.2), doc="the search ends when the trust region is below this (of "
                                                     "a lin knob's span, of a log knob's value)")
    max_iterations: int = integer(15, ge=1, le=200, doc="most candidates re-verified before close gives up")
    global_samples: int = integer(-1, ge=-1, le=1000,
                                  doc="Latin-hypercube points of the global stage over the knobs a cheap bench "
                                      "reads alone (the AFE's), run when the start fails: -1 (default) 8 per "
                                      "such knob, at least 24; 0: no global stage (the local method alone)")
    choose: str = text("screen", choices=("screen", "all"),
                       doc="how close picks among the circuit choices: screen (default) ranks every combination "
                           "by its start's smallest margin where the specs bind and closes them in that order "
                           "until one passes; all closes every combination and keeps the passing one with the "
                           "best objective")

    @property
    def goal(self) -> tuple[str, str]:
        """(``min`` | ``max``, what): what is ``power_chip``, ``area``, a figure or a knob key."""
        sense, _, what = self.objective.strip().partition(" ")
        what = what.strip()
        return sense, OBJECTIVES.get(what, what)

    def validate(self, path, source, raw):
        if not self.knobs:
            raise ConfigError(source, f"{path}.knobs", raw.get("knobs"), "at least one knob: "
                              "\"design.key\" = [\"min\", \"max\"]")
        if len(self.knobs) > MAX_KNOBS:
            raise ConfigError(source, f"{path}.knobs", f"{len(self.knobs)} knobs", f"at most {MAX_KNOBS} knobs")
        sense, what = self.goal
        if sense not in ("min", "max") or not what:
            raise ConfigError(source, f"{path}.objective", self.objective,
                              "\"min X\" or \"max X\" (X: power, area, a figure or a knob key)")


def check(close: CloseSettings, design, source: str, raw: dict) -> CloseSettings:
    """The knobs against the design: each a continuous key the design sets, bounds in its unit
    and within what the design file accepts for it; the objective something close can evaluate.
    Returns the table with the knobs' bounds in SI."""
    knobs = tuple(_choice(k, design, source) if k.choices else _knob(k, design, source) for k in close.knobs)
    combos = 1
    for k in knobs:
        combos *= len(k.choices) or 1
    if combos > MAX_COMBINATIONS:
        raise ConfigError(source, "close.knobs", f"{combos} combinations of choices",
                          f"at most {MAX_COMBINATIONS} combinations (close solves the numeric knobs for each)")
    sense, what = close.goal
    keys = {k.name for k in knobs if not k.choices}
    for k in knobs:
        for i, key in enumerate(k.tied):
            if key in {j.name for j in knobs} or any(key in j.tied for j in knobs if j is not k):
                raise ConfigError(source, f"close.knobs.{k.name}.tied[{i}]", key,
                                  "a key no other knob moves or ties (one knob per design key)")
    figures = figures_of(design)
    area = not hasattr(design, "gate_area") or design.gate_area() is not None
    if what not in figures and not (what == "area" and area) and what not in keys:
        raise ConfigError(source, "close.objective", close.objective,
                          "min or max of power, " + ("area, " if area else "") + "one of the knobs ("
                          + ", ".join(sorted(keys)) + ") or a figure: " + ", ".join(figures))
    return dataclasses.replace(close, knobs=knobs)


def figures_of(design) -> dict:
    """The figures a spec of ``design`` can name: its suite's (a pixel read by role), else the dual pixel's."""
    from .figures import FIGURES
    return getattr(getattr(design, "suite", None), "FIGURES", None) or FIGURES


def field_of(design_cls, key: str):
    """The dataclass field a dotted design key names, or None."""
    cls, f = design_cls, None
    for part in key.split("."):
        if cls is None or not dataclasses.is_dataclass(cls):
            return None
        fields = {x.name: x for x in dataclasses.fields(cls) if x.metadata.get("kind", "skip") != "skip"}
        f = fields.get(part)
        if f is None:
            return None
        cls = f.metadata.get("cls") if f.metadata.get("kind") == "table" else None
    return f


def value_of(design, key: str):
    """The value of a dotted design key in a loaded design (SI)."""
    obj = design
    for part in key.split("."):
        obj = getattr(obj, part)
    return obj


def _field(k: Knob, design, source: str):
    """The schema field of a knob's key, refused when the key is not one close may move."""
    path = f"close.knobs.{k.name}"
    head = k.name.split(".")[0]
    if head in FIXED:
        raise ConfigError(source, path, k.name, "a design key close may change, not " + FIXED[head])
    if head in UNREAD:
        raise ConfigError(source, path, k.name, f"a key a spec depends on: no measurement of pixelkit verify "
                          f"reads [{head}], so no spec moves with it")
    f = field_of(type(design), k.name)
    if f is None:
        raise ConfigError(source, path, k.name, "a numeric key of the design file, like pixel.sf_bias, "
                          "pixel.v_fd_reset, pixel.devices.rst_w, primary.timing.s1_off, primary.t_int, afe.c13, "
                          "or a circuit choice with choices, like pixel.gate_drive (docs/design-file.md)")
    return f


def _choice(k: Knob, design, source: str) -> Knob:
    """A circuit choice: a text key whose schema lists its values; every choice one of them."""
    path = f"close.knobs.{k.name}"
    meta = _field(k, design, source).metadata
    allowed = meta.get("choices")
    if meta.get("kind") != "str" or not allowed:
        raise ConfigError(source, f"{path}.choices", list(k.choices), "choices of a key that names a circuit "
                          "choice (a text key with a fixed set of values, like pixel.gate_drive)")
    for i, c in enumerate(k.choices):
        if c not in allowed:
            raise ConfigError(source, f"{path}.choices[{i}]", c, f"one of {', '.join(allowed)}")
    return dataclasses.replace(k, dim="")


def _knob(k: Knob, design, source: str) -> Knob:
    path = f"close.knobs.{k.name}"
    meta = _field(k, design, source).metadata
    if meta.get("kind") == "int":
        raise ConfigError(source, path, k.name, "a continuous quantity: close does not choose whole numbers "
                          "(rows, cols, secondary_per_pixel)")
    if meta.get("kind") != "qty":
        raise ConfigError(source, path, k.name, "a numeric key (a quantity or a number), not a "
                          + {"str": "text", "ident": "name", "bool": "flag", "table": "table",
                             "list": "list", "map": "table of tables"}.get(meta.get("kind"), "value"))
    dim = meta["dim"]
    lo = _bound(k.min, dim, f"{path}.min", source, meta)
    hi = _bound(k.max, dim, f"{path}.max", source, meta)
    if not hi - lo > 1e-9 * max(abs(lo), abs(hi)):
        raise ConfigError(source, f"{path}.max", k.max, f"a bound above min ({k.min!r})")
    if k.scale == "log" and lo <= 0:
        raise ConfigError(source, f"{path}.min", k.min, "a bound > 0 (scale = \"log\")")
    grid = None
    if k.step is not None:
        grid = _bound(k.step, dim, f"{path}.step", source, None)
        if not (hi - lo) * 1e-9 <= grid < hi - lo:   # issue 44: "1e-300 nA" was taken (no grid at all)
            raise ConfigError(source, f"{path}.step", k.step, "a step below the span max - min and at least "
                              "1e-9 of it (a grid of at most a billion points)")
    for i, key in enumerate(k.tied):
        tpath = f"{path}.tied[{i}]"
        if key == k.name:
            raise ConfigError(source, tpath, key, "another design key than the knob's own")
        try:
            tmeta = _field(dataclasses.replace(k, name=key), design, source).metadata
        except ConfigError as exc:
            raise ConfigError(source, tpath, key, exc.allowed) from None
        if tmeta.get("kind") != "qty" or tmeta.get("dim") != dim:
            raise ConfigError(source, tpath, key, f"a numeric key of the same unit as {k.name}")
        _bound(k.min, dim, tpath, source, tmeta)
        _bound(k.max, dim, tpath, source, tmeta)
    return dataclasses.replace(k, lo=lo, hi=hi, grid=grid, dim=dim, unit_required=bool(meta.get("unit_required")))


def _bound(value, dim: str, path: str, source: str, meta) -> float:
    """A bound in SI: a quantity of the key's unit (a plain number only for a dimensionless key),
    finite, and within what the design file accepts for that key."""
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise ConfigError(source, path, value, f"a quantity like '{DIMENSIONS[dim][1]}'")
    if isinstance(value, float) and not math.isfinite(value):
        raise ConfigError(source, path, value, "a finite value")
    x = quantity(value, dim, path, source)
    if meta is not None:
        check_range(x, meta, path, source, value)
    return x
