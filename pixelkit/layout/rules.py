"""The layout rules the kit knows, checked on a design before anything is drawn.

Each violation raises :class:`RuleError` naming the rule, the place (cell) and
the numbers involved. ``cells.check_at_load`` runs every rule the design file
alone decides - including the layer map, the grid and a dry run of the cells -
when a design is loaded, so every command refuses what ``layout`` would refuse.
"""
from __future__ import annotations

import math

from ..errors import PixelkitError

#: Largest relative change of the mask-opening area that snapping to the grid may cause.
GRID_AREA_TOLERANCE = 0.01
#: Layers that hold real geometry and must each have their own (layer, datatype).
_DRAWN = ("pd", "active", "poly", "contact", "metal1", "shield", "opening", "boundary")


class RuleError(PixelkitError):
    def __init__(self, rule: str, place: str, detail: str, field: str = "", value=None):
        self.rule, self.place, self.detail, self.field, self.value = rule, place, detail, field, value
        super().__init__(f"layout rule {rule} broken in {place}: {detail}")


def check(design) -> None:
    r = design.tech.rules
    for which in ("primary", "secondary"):
        sub = getattr(design, which)
        place = f"{which.upper()} cell"
        side = min(sub.pd_width, sub.pd_height)
        if side < r.min_pd_side - 1e-12:
            f = "pd_width" if sub.pd_width <= sub.pd_height else "pd_height"
            raise RuleError("min_pd_side", place, f"PD side {side * 1e6:.3g} um < {r.min_pd_side * 1e6:.3g} um",
                            f"{which}.{f}", side)
        for dim, size in (("width", sub.pd_width), ("height", sub.pd_height)):
            if size + 2 * r.pd_to_cell_edge > sub.pitch + 1e-12:
                raise RuleError("pd_to_cell_edge", place,
                                f"PD {dim} {size * 1e6:.3g} um + 2 x {r.pd_to_cell_edge * 1e6:.3g} um "
                                f"exceeds the {sub.pitch * 1e6:.3g} um cell", f"{which}.pd_{dim}", size)
        if sub.mask_opening is not None:
            s = math.sqrt(sub.mask_opening)
            where = f"{which}.mask_opening"
            if s < r.min_opening_side - 1e-12:
                raise RuleError("min_opening_side", place,
                                f"opening {sub.mask_opening * 1e12:.3g} um2 is {s * 1e6:.3g} um wide "
                                f"< {r.min_opening_side * 1e6:.3g} um", where, sub.mask_opening)
            room = min(sub.pd_width, sub.pd_height) - 2 * r.opening_to_pd_edge
            if s > room + 1e-12:
                raise RuleError("opening_to_pd_edge", place,
                                f"opening {s * 1e6:.3g} um wide leaves less than "
                                f"{r.opening_to_pd_edge * 1e6:.3g} um to the PD edge", where, sub.mask_opening)
            drawn = round(s / r.grid) * r.grid
            change = abs(drawn ** 2 - sub.mask_opening) / sub.mask_opening
            if change > GRID_AREA_TOLERANCE:
                raise RuleError("grid_resolves_opening", place,
                                f"the {r.grid * 1e9:g} nm grid draws the {sub.mask_opening * 1e12:.4g} um2 "
                                f"opening as {drawn ** 2 * 1e12:.4g} um2 ({change * 100:.1f} % off, more than "
                                f"{GRID_AREA_TOLERANCE * 100:g} %)", where, sub.mask_opening)


def check_layers(tech) -> None:
    """Every drawn layer on its own (layer, datatype): two on one would merge their shapes."""
    seen = {}
    for name in _DRAWN:
        lay = getattr(tech.layers, name)
        key = (lay.layer, lay.datatype)
        if key in seen:
            raise RuleError("distinct_layers", f"technology {tech.name}",
                            f"layers.{name} and layers.{seen[key]} are both GDS {key[0]}/{key[1]}",
                            f"layers.{name}", f"{key[0]}/{key[1]}")
        seen[key] = name
