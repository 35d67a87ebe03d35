"""The layout rules the kit knows, checked on a design before anything is drawn.

Each violation raises :class:`RuleError` naming the rule, the place (cell) and
the numbers involved.
"""
from __future__ import annotations

import math

from ..errors import PixelkitError


class RuleError(PixelkitError):
    def __init__(self, rule: str, place: str, detail: str):
        self.rule, self.place = rule, place
        super().__init__(f"layout rule {rule} broken in {place}: {detail}")


def check(design) -> None:
    r = design.tech.rules
    for which in ("primary", "secondary"):
        sub = getattr(design, which)
        place = f"{which.upper()} cell"
        side = min(sub.pd_width, sub.pd_height)
        if side < r.min_pd_side - 1e-12:
            raise RuleError("min_pd_side", place, f"PD side {side * 1e6:.3g} um < {r.min_pd_side * 1e6:.3g} um")
        for dim, size in (("width", sub.pd_width), ("height", sub.pd_height)):
            if size + 2 * r.pd_to_cell_edge > sub.pitch + 1e-12:
                raise RuleError("pd_to_cell_edge", place,
                                f"PD {dim} {size * 1e6:.3g} um + 2 x {r.pd_to_cell_edge * 1e6:.3g} um "
                                f"exceeds the {sub.pitch * 1e6:.3g} um cell")
        if sub.mask_opening is not None:
            s = math.sqrt(sub.mask_opening)
            if s < r.min_opening_side - 1e-12:
                raise RuleError("min_opening_side", place,
                                f"opening {sub.mask_opening * 1e12:.3g} um2 is {s * 1e6:.3g} um wide "
                                f"< {r.min_opening_side * 1e6:.3g} um")
            room = min(sub.pd_width, sub.pd_height) - 2 * r.opening_to_pd_edge
            if s > room + 1e-12:
                raise RuleError("opening_to_pd_edge", place,
                                f"opening {s * 1e6:.3g} um wide leaves less than "
                                f"{r.opening_to_pd_edge * 1e6:.3g} um to the PD edge")
