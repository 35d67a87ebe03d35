"""The kit's own layout rules on a design (PD and opening sizes), checked before anything is drawn.

Each violation raises :class:`RuleError` naming the rule, the place (cell), the numbers
involved and the design field that breaks it. The generators raise the same error when
the devices do not fit (``pixel.py``); ``fit.py`` runs both without writing anything. The
foundry's own rules are the deck's business (``signoff/drc.py``).
"""
from __future__ import annotations

import math

from ..errors import PixelkitError

#: Largest relative change of the mask-opening area that snapping to the grid may cause.
GRID_AREA_TOLERANCE = 0.01


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
