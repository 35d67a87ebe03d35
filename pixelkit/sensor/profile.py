"""Measuring a trapezoidal 1-D signal profile to sub-pixel precision.

A moving uniform object exposed through a window leaves a trapezoid along the
motion (two linear ramps of width r, a flat part p: the convolution of two
boxes). Each pixel averages that trapezoid over its light-collecting aperture.
The measurement fits the four numbers (left foot, r, p, height) of a trapezoid
averaged over the known apertures to the samples by least squares, starting from
the level crossings (ramp = 2 (x75 - x25), total = FWHM + ramp), which alone are
exact only for ramps longer than two pixels.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from ..errors import PixelkitError


def crossing(p: np.ndarray, level: float, from_left: bool) -> float:
    """Fractional sample index where ``p`` first reaches ``level`` (linear interpolation)."""
    idx = np.nonzero(p >= level)[0]
    if idx.size == 0:
        raise PixelkitError("the profile never reaches the level: nothing to measure")
    if from_left:
        i = idx[0]
        if i == 0:
            return 0.0
        a, b = p[i - 1], p[i]
        return (i - 1) + (level - a) / (b - a)
    i = idx[-1]
    if i == p.size - 1:
        return float(i)
    a, b = p[i], p[i + 1]
    return i + (a - level) / (a - b)


def _cumulative(x, foot, r, p, height):
    """Integral from -inf to x of the trapezoid (foot, ramp r, flat p, height)."""
    q = lambda z: 0.5 * np.maximum(z, 0.0) ** 2  # noqa: E731
    z = x - foot
    return height / r * (q(z) - q(z - r) - q(z - r - p) + q(z - 2 * r - p))


def averaged(lo, hi, foot, r, p, height):
    """The trapezoid averaged over apertures [lo, hi]."""
    return (_cumulative(hi, foot, r, p, height) - _cumulative(lo, foot, r, p, height)) / (hi - lo)


def trapezoid(p, pitch: float = 1.0, origin: float = 0.0, floor: float = 1e-6, apertures=None) -> dict:
    """Sub-pixel edges of a single-peaked profile: positions in the units of ``pitch``.

    ``apertures`` = (lo, hi) arrays of each sample's collecting interval (default:
    the whole pixel).
    """
    p = np.asarray(p, dtype=float)
    top = float(p.max())
    if not top > 0:
        raise PixelkitError("the profile is empty (no signal)")
    if apertures is None:
        edges = origin + np.arange(p.size + 1) * pitch
        apertures = (edges[:-1], edges[1:])
    lo, hi = (np.asarray(a, dtype=float) for a in apertures)
    centres = 0.5 * (lo + hi)
    pitch = float(np.median(np.diff(centres))) if centres.size > 1 else pitch
    pos = lambda i: float(np.interp(i, np.arange(p.size), centres))  # noqa: E731
    x = {f: (pos(crossing(p, f * top, True)), pos(crossing(p, f * top, False))) for f in (0.25, 0.5, 0.75)}
    ramp = (x[0.75][0] - x[0.25][0]) + (x[0.25][1] - x[0.75][1])      # = 2 (x75 - x25) averaged
    fwhm = x[0.5][1] - x[0.5][0]
    support = np.nonzero(p > floor * top)[0]
    r0 = max(ramp, 0.05 * pitch)
    x0 = [x[0.5][0] - r0 / 2, r0, max(fwhm - r0, 0.0), top]
    fit = least_squares(lambda q: averaged(lo, hi, *q) - p, x0, x_scale=[pitch, pitch, pitch, top],
                        bounds=([-np.inf, 1e-3 * pitch, 0.0, 0.0], [np.inf, np.inf, np.inf, np.inf]))
    foot, r, flat, height = fit.x
    return {"left": foot, "right": foot + 2 * r + flat, "half_left": foot + r / 2,
            "half_right": foot + 1.5 * r + flat, "fwhm": r + flat, "edge": r, "total": 2 * r + flat,
            "flat": flat, "support": int(support.size) * pitch, "peak": height}


def centroid(p, pitch: float = 1.0, origin: float = 0.0) -> float:
    p = np.asarray(p, dtype=float)
    x = origin + (np.arange(p.size) + 0.5) * pitch
    return float((p * x).sum() / p.sum())
