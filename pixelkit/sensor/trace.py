"""Trace extraction from a secondary image (linearised to charge).

The bright source's trace along its row is the convolution of its path (length
D, from the source's centre at the start of the exposure to its centre at the
end) with its own width w: a trapezoid whose flat-to-flat half-maximum width is
max(D, w) and whose ramps are min(D, w). The background is removed by
subtracting the rows just outside the source's band. Which of the two is D is
decided by the source's width on the primary image (its exposure is too short to
smear it, but its pixels are coarse: it only picks the branch). The path is
centred on the trapezoid's centre.
"""
from __future__ import annotations

import numpy as np

from ..errors import PixelkitError
from .exposure import Cells
from .profile import trapezoid


def brightest_row(image: np.ndarray) -> int:
    return int(np.argmax(image.max(axis=1)))


def background_removed(image: np.ndarray, row: int, gap: int) -> np.ndarray:
    """The row minus the mean of the rows ``gap`` above and below it (those that exist)."""
    refs = [r for r in (row - gap, row + gap) if 0 <= r < image.shape[0]]
    if not refs:
        raise PixelkitError("the image has no rows outside the source's band to estimate the background")
    return image[row] - np.mean([image[r] for r in refs], axis=0)


def source_width(primary_charge: np.ndarray, cols: Cells, gap: int) -> float:
    """Width of the bright source on the primary image (m)."""
    row = brightest_row(primary_charge)
    p = np.clip(background_removed(primary_charge, row, gap), 0, None)
    return trapezoid(p, apertures=(cols.lo, cols.hi))["fwhm"]


def extract(secondary_charge: np.ndarray, cols: Cells, width_hint: float, gap: int) -> dict:
    """Start and end (m, along the row) of the source's path during the secondary exposure."""
    row = brightest_row(secondary_charge)
    p = np.clip(background_removed(secondary_charge, row, gap), 0, None)
    m = trapezoid(p, apertures=(cols.lo, cols.hi))
    longer, shorter = m["fwhm"], m["edge"]
    d = longer if abs(shorter - width_hint) <= abs(longer - width_hint) else shorter
    if not d > 0:
        raise PixelkitError("no trace on the secondary image: no motion to measure")
    centre = 0.5 * (m["left"] + m["right"])
    return {"row": row, "start_m": centre - d / 2, "end_m": centre + d / 2, "length_m": d,
            "source_width_m": shorter if d == longer else longer, "profile_fit": m}
