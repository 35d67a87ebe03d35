"""Conversion gain, full well and photoactive area ([Thesis2019] eq. 3.6, table 3.2)."""
from __future__ import annotations

from ..constants import Q


def rectangle(width: float, height: float) -> tuple[float, float]:
    """Area (m^2) and perimeter (m) of a rectangular photodiode."""
    return width * height, 2.0 * (width + height)


def photoactive_area(width: float, height: float, mask_opening: float | None) -> float:
    """Light-collecting area: the PD, or the metal-mask opening over it."""
    area = width * height
    if mask_opening is None:
        return area
    if not 0 < mask_opening <= area:
        raise ValueError(f"mask opening {mask_opening:g} m^2 must be > 0 and <= the PD area {area:g} m^2")
    return mask_opening


def conversion_gain(c: float) -> float:
    """CG = q / C in V per electron (eq. 3.6)."""
    return Q / c


def full_well(swing: float, c: float) -> float:
    """Full well (electrons) = swing * C / q at a fixed C, as table 3.2 quotes it."""
    return swing * c / Q


def full_well_cv(node, v_reset: float, swing: float) -> float:
    """Full well with C(V): the charge between the reset bias and reset - swing, in e-."""
    return float(node.charge(v_reset) - node.charge(v_reset - swing)) / Q
