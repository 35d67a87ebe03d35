"""Source/drain diffusion geometry of a MOSFET, shared by netlists and analytic models.

Each diffusion is ``W x diff_ext`` (the technology's contacted diffusion length).
The perimeter includes the gate edge (BSIM4 ``permod = 1``); the analytic node
model splits it into the gate edge (W, cjswg) and the rest (PS - W, cjsw).
"""
from __future__ import annotations


def diffusion(w: float, diff_ext: float) -> tuple[float, float]:
    """(area m^2, perimeter m) of one source or drain of a transistor of width ``w``."""
    return w * diff_ext, 2.0 * (w + diff_ext)
