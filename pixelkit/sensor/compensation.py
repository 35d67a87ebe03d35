"""Two sensors scanning in opposite directions undo the rolling-shutter distortion ([Rychazhnikov2008b]).

Vertical motion. One sensor sees the object move with its scan, the other against
it; their images have heights (``rolling``, units rows and line times, s = v/v_H)

    L'' = (h + s H) / (1 - s)      (stretched)
    L'  = (h + s H) / (1 + s)      (compressed)

Both numerators are the same, so L''(1 - s) = L'(1 + s) and

    s = (L'' - L') / (L'' + L')
    h = L'(1 + s) - s H = (2 L' L'' - H (L'' - L')) / (L' + L'')

linear in the two heights: no quadratic. The article's quadratic
2h^2 - (3L' + L'')h + 2L'L'' - H(L'' - L') = 0 follows (with L' and L'' swapped
in its linear coefficient) from its size formulas
L = s (H + h) / (1 -+ s) + h, whose upward form the image simulation refutes;
``published_height`` solves it as printed, for comparison.

The rows of each image are then rescaled by h / L about the image's centre (the
object's position when its centre row is half-way through the accumulation).

Horizontal motion. The parallelograms lean opposite ways, row y being shifted
by +s y in one sensor and -s y in the other; the mean of a row's two positions
(dx = (dx1 + dx2) / 2, dy = dy1 = dy2) is that of a global shutter exposing all
rows at the middle of the frame, so the averaged image is the global-shutter
image (motion blur l + s H included: no frame-level processing removes that).
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import PixelkitError
from .profile import centroid


def vertical(l_a: float, l_b: float, window: float) -> dict:
    """True height (rows) and speed (fraction of the scan speed) from the two images' heights."""
    lc, ls = min(l_a, l_b), max(l_a, l_b)
    if not lc > 0:
        raise PixelkitError(f"image heights must be > 0 rows, got {l_a:g} and {l_b:g}")
    s = (ls - lc) / (ls + lc)
    h = (2 * lc * ls - window * (ls - lc)) / (lc + ls)
    return {"h_rows": h, "speed": s, "compressed_rows": lc, "stretched_rows": ls}


def published_height(l_compressed: float, l_stretched: float, window: float) -> float:
    """Root 0 < h < L' of the article's 2h^2 - (3L' + L'')h + 2L'L'' - H(L'' - L') = 0 (nan if none)."""
    lc, ls = l_compressed, l_stretched
    roots = np.roots([2.0, -(3 * lc + ls), 2 * lc * ls - window * (ls - lc)])
    ok = [r.real for r in roots if abs(r.imag) < 1e-12 and 0 < r.real < lc]
    return float(ok[0]) if ok else math.nan


def rescale_rows(image: np.ndarray, centre: float, factor: float) -> np.ndarray:
    """Rows stretched by ``factor`` about ``centre`` (row coordinate; pixel i spans [i, i + 1])."""
    y = np.arange(image.shape[0]) + 0.5
    src = centre + (y - centre) / factor
    return np.stack([np.interp(src, y, image[:, c], left=0.0, right=0.0) for c in range(image.shape[1])], axis=1)


def average_rows(image_a: np.ndarray, image_b: np.ndarray) -> np.ndarray:
    """Image a with each row moved to the mean of its position in a and b (row centroids)."""
    x = np.arange(image_a.shape[1]) + 0.5
    out = np.zeros_like(image_a)
    for r in range(image_a.shape[0]):
        if image_a[r].sum() <= 0 or image_b[r].sum() <= 0:
            continue
        shift = 0.5 * (centroid(image_b[r]) - centroid(image_a[r]))
        out[r] = np.interp(x - shift, x, image_a[r], left=0.0, right=0.0)
    return out
