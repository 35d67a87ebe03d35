"""The ``[spec]`` and ``[verify]`` tables of a design file, validated when the file loads.

A spec is one figure the kit measures (``verify.figures``) with a ``min`` and / or a
``max`` (and a ``typ``, shown but not checked, as a CACE datasheet's "typical"), the
unit the sign-off table shows it in, and the conditions it must hold over. Shaped as a
CACE datasheet parameter (``spec: {minimum, typical, maximum}`` plus ``conditions``),
written in the design file's own convention (values carry their unit)::

    [spec.conversion_gain_primary]
    min = "3.5 uV/e-"
    typ = "4.0 uV/e-"
    note = "[Thesis2019] table 3.2"

    [spec.cg_hot]                     # a second spec on the same figure
    figure = "conversion_gain_primary"
    min = "3.2 uV/e-"
    temperatures = ["85 degC"]

``[verify]`` holds the sign-off grid: process corners (default every corner of the model
library), temperatures (-20, 27, 85 degC), supplies (+-10 %), Monte Carlo samples and
seed. A spec's own ``corners`` / ``temperatures`` / ``supplies`` restrict it to part of
that grid. Everything is checked here, before any simulation: an unknown figure, a unit
that does not fit the figure, min above max, a corner the model library lacks.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

from ..errors import ConfigError
from ..schema import flag, ident, integer, items, limit, num, qty, text
from ..units import quantity
from .figures import FIGURES, ROLE_FIGURES, unit_scale, units_for

_TEMP = (213.15, 473.15)


@dataclass(frozen=True)
class Spec:
    """One specification (``[spec.<name>]``): a figure, its limits and the conditions it holds over."""
    figure: str = text("", doc="the figure (default: the table's name); one of the figures listed in "
                               "docs/verify.md")
    min: object = limit(doc="lower limit with its unit (or a plain number in `unit`)")
    max: object = limit(doc="upper limit with its unit (or a plain number in `unit`)")
    typ: object = limit(doc="typical value: shown, not checked (CACE's 'typical')")
    unit: str = text("", doc="unit of the sign-off table (default: the figure's unit); must fit the figure")
    corners: tuple = items(ident(), (), doc="process corners it must hold at (default: the [verify] grid's)")
    temperatures: tuple = items(qty("K", plausible=_TEMP), (), doc="temperatures it must hold at (default: the "
                                                                   "[verify] grid's)")
    supplies: tuple = items(num(ge=-0.5, le=0.5), (), doc="supply deviations it must hold at, like \"-10 %\" "
                                                          "(default: the [verify] grid's)")
    mc: bool = flag(True, doc="compute its Monte Carlo yield (when [verify] mc > 0 and mismatch moves the figure)")
    note: str = text("", doc="where the limit comes from (shown in the table)")
    name: str = field(default="", metadata=dict(kind="skip"))
    lo: float | None = field(default=None, metadata=dict(kind="skip"))
    hi: float | None = field(default=None, metadata=dict(kind="skip"))
    typical: float | None = field(default=None, metadata=dict(kind="skip"))
    #: the figures this spec may name (the dual pixel's; ``RoleSpec``: a pixel read by role)
    TABLE: ClassVar[dict] = FIGURES

    @property
    def fig(self):
        return self.TABLE[self.figure or self.name]

    @property
    def shown_unit(self) -> str:
        return self.unit or self.fig.unit

    def validate(self, path, source, raw):
        name = path.rsplit(".", 1)[-1]
        fig_name = self.figure or name
        if fig_name not in self.TABLE:
            where = f"{path}.figure" if self.figure else path
            raise ConfigError(source, where, fig_name, "a figure the kit measures: " + ", ".join(self.TABLE)
                              + ("" if self.figure else " (or name it with figure = \"...\")"))
        fig = self.TABLE[fig_name]
        unit = self.unit or fig.unit
        if unit_scale(unit, fig.dim) is None:
            raise ConfigError(source, f"{path}.unit", self.unit, f"a unit of {fig.name} ({units_for(fig.dim)})")
        vals = {k: _si(getattr(self, k), fig, unit, f"{path}.{k}", source) for k in ("min", "max", "typ")}
        lo, hi = fig.plausible
        for k, v in vals.items():   # a limit no real figure reaches always passes (or fails): a typo
            if v is not None and not lo < v < hi:
                raise ConfigError(source, f"{path}.{k}", getattr(self, k),
                                  f"a value strictly between {_edge(lo, unit, fig)} and {_edge(hi, unit, fig)} "
                                  f"{unit} (the values a real {fig.name} can have; a limit at or beyond them "
                                  "never decides anything)".replace("  ", " "))
        if vals["min"] is None and vals["max"] is None:
            raise ConfigError(source, path, raw, "a spec with a min and / or a max")
        if vals["min"] is not None and vals["max"] is not None and vals["min"] > vals["max"]:
            raise ConfigError(source, f"{path}.max", self.max, f"a value >= min ({self.min!r})")
        object.__setattr__(self, "lo", vals["min"])
        object.__setattr__(self, "hi", vals["max"])
        object.__setattr__(self, "typical", vals["typ"])


@dataclass(frozen=True)
class RoleSpec(Spec):
    """A spec of a pixel read by role (families ``pixel4t`` and ``netlist``): its figures are
    ``verify.figures.ROLE_FIGURES``."""
    TABLE: ClassVar[dict] = ROLE_FIGURES


def _edge(x: float, unit: str, fig) -> str:
    from .figures import shown
    return f"{shown(x, unit, fig.dim):.6g}"


def _si(value, fig, unit: str, where: str, source: str) -> float | None:
    """A limit in SI: a string with its unit, or a plain number read in ``unit``."""
    if value is None:
        return None
    if isinstance(value, str):
        return quantity(value, fig.dim, where, source)  # "60 dB" is an amplitude ratio, "5 %" 0.05
    kind, scale = unit_scale(unit, fig.dim)
    if kind == "dB":
        return 10.0 ** (value / 20.0)
    return value / 100.0 if kind == "%" else value * scale


@dataclass(frozen=True)
class VerifySettings:
    """The sign-off grid of ``pixelkit verify`` and of the report's sign-off table."""
    corners: tuple = items(ident(), (), doc="process corners (default: every corner of the technology's model "
                                            "library)")
    temperatures: tuple = items(qty("K", plausible=_TEMP), (253.15, 300.15, 358.15),
                                doc="die temperatures")
    supplies: tuple = items(num(ge=-0.5, le=0.5), (-0.1, 0.0, 0.1),
                            doc="supply deviations from the technology's supply, like \"-10 %\"")
    mc: int = integer(0, ge=0, le=100000, doc="Monte Carlo samples at the nominal condition (0: none)")
    seed: int = integer(1, ge=0, le=2**31 - 1, doc="Monte Carlo seed: the same seed gives the same draws")
    confidence: float = num(0.95, gt=0.5, lt=1.0, doc="level of the Clopper-Pearson yield intervals")
    min_yield: float = num(0.0, ge=0.0, le=1.0, doc="a spec whose yield interval lies below this fails, like "
                                                   "\"99 %\" (0: yield reported, not checked)")
    mismatch: str = text("auto", choices=("auto", "library", "pelgrom"),
                         doc="Monte Carlo draws: the model library's own mismatch statistics, the kit's "
                             "Pelgrom draw per device (technology [mismatch] mos_avt_n / mos_avt_p), or "
                             "auto: the library's where it has them")


def check_conditions(design, tech) -> None:
    """Every corner a spec or the grid names exists in the technology's model library."""
    have = tech.models.corners
    allowed = f"a corner of the model library: {', '.join(sorted(have))}"
    for c in design.verify.corners:
        if c not in have:
            raise ConfigError(design.source or "", "verify.corners", c, allowed)
    for s in design.spec:
        for c in s.corners:
            if c not in have:
                raise ConfigError(design.source or "", f"spec.{s.name}.corners", c, allowed)
