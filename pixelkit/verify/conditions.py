"""Operating conditions of the sign-off grid: process corner x temperature x supply.

A condition changes three things of a design and nothing else: the model library's
corner (the technology's corner table: MOS sections and, where the library has them,
the diode sections it pairs with them; the MIM capacitors' corner factor on the AFE's
capacitors, ``[models.mim_corners]``, tech/mimcorner.py), the die temperature (every deck's ``.temp``,
hence the device models and the kit's dark-current law), and the supply (the
technology's ``supply``: VDD of the pixels, columns, AFE and the clock levels). The
reset drains (``pixel.v_pd_reset``, ``v_fd_reset``) and ``afe.vref`` are references a
chip regulates, and stay as designed.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, replace

from ..errors import ConfigError


@dataclass(frozen=True, order=True)
class Condition:
    corner: str
    temperature: float   # K
    supply: float        # relative deviation from the technology's supply

    @property
    def label(self) -> str:
        return f"{self.corner} {self.temperature - 273.15:g}degC {self.supply * 100:+g}%"

    def as_dict(self) -> dict:
        return {"corner": self.corner, "temperature_C": round(self.temperature - 273.15, 6),
                "supply_dev": self.supply}


def nominal(design) -> Condition:
    return Condition(design.corner_name, design.temperature, 0.0)


def grid(design, corners=None, temperatures=None, supplies=None) -> list[Condition]:
    """Every condition of the grid: the arguments, else the design's ``[verify]`` table
    (corners: every corner of the model library)."""
    v = design.verify
    corners = tuple(corners or v.corners or sorted(design.tech.models.corners))
    temps = tuple(temperatures or v.temperatures)
    sups = tuple(supplies if supplies is not None else v.supplies)
    have = design.tech.models.corners
    for c in corners:
        if c not in have:
            raise ConfigError(design.source, "--corners", c, f"a corner of the model library: {', '.join(sorted(have))}")
    return [Condition(c, t, s) for c, t, s in itertools.product(corners, temps, sups)]


def at(design, cond: Condition):
    """``design`` at condition ``cond`` (corner, temperature, supply)."""
    supply = design.tech.supply * (1.0 + cond.supply)
    for what, v in (("pixel.v_pd_reset", design.pixel.v_pd_reset), ("pixel.v_fd_reset", design.pixel.v_fd_reset),
                    ("afe.vref", design.afe.vref), ("pixel.swing", design.pixel.swing)):
        if v >= supply and not (what.endswith("reset") and v == supply):
            raise ConfigError(design.source, what, v, f"a level below the supply at condition {cond.label} "
                              f"({supply:g} V)")
    tech = replace(design.tech, supply=supply) if cond.supply else design.tech
    k = design.tech.mim_corner.get(cond.corner, 1.0)
    a = design.afe
    afe = a if k == 1.0 else replace(a, c11=a.c11 * k, c12=a.c12 * k, c13=a.c13 * k)
    return replace(design, corner=cond.corner, temperature=cond.temperature, tech=tech, afe=afe)


def spec_conditions(spec, grid: list) -> list:
    """The conditions of ``grid`` a spec holds at (its own corners / temperatures / supplies, if any)."""
    return [c for c in grid
            if (not spec.corners or c.corner in spec.corners)
            and (not spec.temperatures or any(abs(c.temperature - t) < 1e-6 for t in spec.temperatures))
            and (not spec.supplies or any(abs(c.supply - s) < 1e-9 for s in spec.supplies))]
