"""The fringe capacitance of one edge of an isolated conductor over a plane (the extraction's per-edge
term, ``capacitance.py``; the corner fields and the top-face covers take their charge from it), and
where on the plane beside the edge it lands.

``fringe``: T. Sakurai and K. Tamaru, "Simple formulas for two- and three-dimensional capacitances",
IEEE Trans. Electron Devices 30(2), 1983: their isolated-line formula less its plate term, per edge.

``landing``: the edge of a thin conductor h over a ground plane (the half-plane; conformal map
``z = (h/pi)(1 + w + ln w)``, potential ``arg(w) / pi``; the plane is w = u > 0, the conductor w < 0).
The plane's point x beyond the edge is ``1 + u + ln u = pi x / h`` (u = 0.278 under the edge) and the
flux between two of its points ``(eps / pi) ln(u2 / u1)``: 0.57 eps of it within h of the edge, 0.28
eps from h to 2 h, falling as h / x further out. ``capacitance._down`` shares an edge's fringe among
the conductors under the strip beside it by this flux, each for its own gap.
"""
from __future__ import annotations

import math
from functools import lru_cache


def fringe(eps: float, t: float, h: float) -> float:
    """Fringe capacitance per length (F/m) of one edge of a conductor of thickness t, h above a plane."""
    return eps * 1.40 * (t / h) ** 0.222


def wide(w: float, t: float, h: float) -> float:
    """How much more fringe an edge of a conductor w wide has than ``fringe`` gives: the cross-section's 2D
    solve (``section.single``: the line alone over the plane, less its plate term w / h, halved) over
    Sakurai and Tamaru's edge. Their formula is a narrow line's: on GF180's metals it is 4 - 10 % above the
    solve at 0.23 um, within 2 - 7 % from 0.5 to 1 um, then low as the edge's field reaches further over the
    plane under a wider conductor (a metal3 plate 10 um wide, 3.5 um up: 1.30 against 0.93 eps per edge, the
    plate -14 %). No constant."""
    from . import section
    return (section.single(w, t, h) - w / h) / 2 / (1.40 * (t / h) ** 0.222)


def width_of(area: float, perimeter: float) -> float:
    """The width of a polygon for its edges' fringe: the short side of the rectangle of the same area and
    perimeter (a rectangle's own short side; a line's width; a square's side)."""
    q = perimeter / 4
    return q - math.sqrt(max(0.0, q * q - area))


@lru_cache(maxsize=4096)
def _u(s: float) -> float:
    """u > 0 with 1 + u + ln u = s (the ground plane's point s h / pi beyond the edge, ``landing``)."""
    lo, hi = -40.0, max(1.0, math.log(abs(s) + 2.0) + 2.0)     # bisection on ln u
    for _ in range(80):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if 1 + math.exp(mid) + mid < s else (lo, mid)
    return math.exp((lo + hi) / 2)


def landing(h: float, x0: float, x1: float) -> float:
    """The flux (in eps / pi per length of edge) an edge h over a plane sends to the plane's strip x0 .. x1
    beyond it: ``ln(u(x1) / u(x0))``, ``1 + u + ln u = pi x / h`` (the half-plane over a ground plane,
    conformal map ``z = (h / pi)(1 + w + ln w)``, potential ``arg(w) / pi``)."""
    return math.log(_u(math.pi * x1 / h) / _u(math.pi * x0 / h))
