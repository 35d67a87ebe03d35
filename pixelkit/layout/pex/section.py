"""The lateral field of two lines of one layer, from their cross-section: Laplace's equation solved in 2D.

Two lines of a layer, w1 and w2 wide, t thick, s apart, with a ground plane ``below`` under their
bottoms (the substrate, or the nearest conductor under the space between them) and, where there is
one, a conductor ``above`` over their tops: the capacitance per length between them and from each to
ground is the 2D electrostatic problem of that cross-section, which is solved here by boundary
elements (the method FastCap2 applies in 3D): each line's outline cut into panels of uniform charge,
finer towards the corners (cosine spacing, where the charge crowds), the ground plane by images
(a panel's image, of opposite charge, mirrored in it), the conductor above as a thin grounded plate
of its own, panelled likewise (wide enough, 12 x the heights beyond the lines, that its ends do not
matter: moving them 2 x further moves the coupling by < 0.1 %). The potential of a straight panel of
uniform charge at a point is closed form (``_ln_integral``); each line at 1 V in turn gives a column of
the Maxwell matrix. In units of the permittivity (the medium is the layer's band, ``Stack.eps_band``).

Why not a formula: Chern et al.'s (IEEE Electron Device Letters 13(1), 1992), which the kit used
before, holds within 5 % of this solve up to a spacing of about the height over the plane, then
overshoots as the field lines leave the gap for the plane instead: +10 .. +20 % at s / h = 1.6,
+25 .. +45 % at 2.6, +40 .. +85 % at 4 (widths 0.25 - 3 um, thicknesses 0.2 / 0.55 um over a plane
1.23 um down; FastCap2 on metal1 lines 0.5 x 50 um: +12.6 % at 2 um, +29.4 % at 3.2 um). Sakurai and
Tamaru's coupling formula (IEEE Trans. Electron Devices 30(2), 1983) and the PDK's sidewall
coefficient (Magic's ``40.512 / (s - 0.053)`` aF/um for metal1) are each 20 % or more off somewhere in
the same range (docs/post-layout.md). The solve has no constant: its only choices are numerical (4
panels per face: the coupling within 1.1 % of 24, on lines 0.23 - 2 um wide, 0.25 - 3.2 um apart).

What the extraction takes from it (``capacitance.capacitances``): the coupling (``pair``), and how much
of a line's edge fringe its neighbour leaves to ground (``kept``: the isolated line's and the pair's
ground capacitance by the same solve; it replaces the law ``s / (s + 0.7 h)`` whose 0.7 was set on a
metal1 pair with FastCap2).
"""
from __future__ import annotations

import math

PANELS = 4          # per face of a line (cosine spacing: fine at the corners): within 1.1 % of 24


def _ln_integral(px, py, ax, ay, bx, by):
    """∫ ln|P - X| dX over each segment a -> b for each point P: the points' arrays (..., n) against the
    segments' (..., m) give (..., n, m)."""
    import numpy as np
    dx, dy = bx - ax, by - ay
    ln = np.hypot(dx, dy)
    tx, ty = (dx / ln)[..., None, :], (dy / ln)[..., None, :]
    rx, ry = px[..., :, None] - ax[..., None, :], py[..., :, None] - ay[..., None, :]
    u = rx * tx + ry * ty                     # along the segment from a
    v = -rx * ty + ry * tx                    # across it
    av = np.abs(v)
    safe = np.where(av > 0, v, 1.0)

    def f(x):                                 # ∫ ln sqrt(x^2 + v^2) dx
        r2 = x * x + v * v
        lg = 0.5 * np.log(np.where(r2 > 0, r2, 1.0))
        return x * lg - x + np.where(av > 0, v * np.arctan(x / safe), 0.0)
    return f(ln[..., None, :] - u) - f(-u)


def _outline(x0, y0, x1, y1, n):
    """Panels (ax, ay, bx, by lists) of a rectangle's outline, ``n`` per face, cosine spaced."""
    corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]
    out = []
    for (ax, ay), (bx, by) in zip(corners, corners[1:]):
        ts = [0.5 - 0.5 * math.cos(math.pi * k / n) for k in range(n + 1)]
        pts = [(ax + (bx - ax) * t, ay + (by - ay) * t) for t in ts]
        out += [(p[0], p[1], q[0], q[1]) for p, q in zip(pts, pts[1:])]
    return out


def _smooth_part(px, py, qx, qy, d):
    """G + ln r / (2 pi) of the Green's function between two grounded planes y = 0 and y = d (a unit line
    charge at q, potential at p): G = ln[(cosh(pi dx / d) - cos(pi (y + y') / d)) / (cosh(pi dx / d) -
    cos(pi (y - y') / d))] / (4 pi), with cosh a - cos b = 2 sinh^2(a / 2) + 2 sin^2(b / 2); smooth
    where r -> 0 (its limit there taken)."""
    import numpy as np
    k = math.pi / d
    dx, dm, dp = px - qx, py - qy, py + qy
    plus = 2 * np.sinh(k * dx / 2) ** 2 + 2 * np.sin(k * dp / 2) ** 2
    minus = 2 * np.sinh(k * dx / 2) ** 2 + 2 * np.sin(k * dm / 2) ** 2
    r2 = dx * dx + dm * dm
    ratio = np.where(r2 > 0, minus / np.where(r2 > 0, r2, 1.0), k * k / 2)
    return (np.log(plus) - np.log(ratio)) / (4 * math.pi)


_GAUSS = ((-0.7745966692414834, 5 / 9), (0.0, 8 / 9), (0.7745966692414834, 5 / 9))


def _maxwell(sets, aboves):
    """Maxwell capacitance matrices (per length, in units of the permittivity) of sets of rectangles (x0, y0,
    x1, y1; every set as many), each over a ground plane y = 0 and, with its ``above`` > 0, under a second
    grounded plane at y = ``above``: an array (sets, k, k). One plane: each panel's image of opposite charge
    mirrored in it (closed form). Two: the Green's function of a line charge between two planes
    (``_smooth_part``): its ln r part closed form, the rest (smooth) by 3-point Gauss quadrature over each
    panel. The sets are solved together (one stacked solve)."""
    import numpy as np
    k = len(sets[0])
    a = np.array([[p for r in rs for p in _outline(*r, PANELS)] for rs in sets], dtype=float)   # (sets, n, 4)
    ax, ay, bx, by = (a[..., c] for c in range(4))
    px, py = (ax + bx) / 2, (ay + by) / 2
    lengths = np.hypot(bx - ax, by - ay)
    aboves = np.asarray(aboves, dtype=float)
    # potential at each panel's middle of unit charge density on each panel: -ln r / (2 pi) + the planes'
    m = -_ln_integral(px, py, ax, ay, bx, by) / (2 * math.pi)
    two = aboves > 0
    if (~two).any():
        m[~two] += _ln_integral(px[~two], py[~two], ax[~two], -ay[~two], bx[~two], -by[~two]) / (2 * math.pi)
    if two.any():
        d = aboves[two][:, None, None]
        for g, wt in _GAUSS:
            qx = (ax + bx)[two] / 2 + g * (bx - ax)[two] / 2
            qy = (ay + by)[two] / 2 + g * (by - ay)[two] / 2
            m[two] += (_smooth_part(px[two][:, :, None], py[two][:, :, None], qx[:, None, :], qy[:, None, :], d)
                       * (wt * lengths[two] / 2)[:, None, :])
    per = a.shape[1] // k
    drive = np.repeat(np.eye(k), per, axis=0)                         # (n, k): each rectangle at 1 V in turn
    sigma = np.linalg.solve(m, np.broadcast_to(drive, (len(sets),) + drive.shape))
    charge = sigma * lengths[..., None]
    return charge.reshape(len(sets), k, per, k).sum(axis=2)


def _nm(x: float) -> int:
    return int(round(x * 1e9))


_PAIRS: dict = {}
_SINGLES: dict = {}


def _solve_pairs(keys) -> None:
    """Solve the pairs ``keys`` ((w1, w2, t, s, below, above) in nm) not yet known, together."""
    todo = sorted({k for k in keys if k not in _PAIRS})
    for i in range(0, len(todo), 256):
        chunk = todo[i:i + 256]
        c = _maxwell([[(-w1, b, 0, b + t), (s, b, s + w2, b + t)] for w1, w2, t, s, b, _u in chunk],
                     [b + t + u if u else 0 for _w1, _w2, t, _s, b, u in chunk])
        for key, m in zip(chunk, c):
            _PAIRS[key] = (-m[0, 1], m[0, 0] + m[0, 1], m[1, 1] + m[1, 0])


def _solve_singles(keys) -> None:
    todo = sorted({k for k in keys if k not in _SINGLES})
    for i in range(0, len(todo), 256):
        chunk = todo[i:i + 256]
        c = _maxwell([[(0, b, w, b + t)] for w, t, b, _u in chunk], [b + t + u if u else 0 for _w, t, b, u in chunk])
        for key, m in zip(chunk, c):
            _SINGLES[key] = m[0, 0]


def _key(w1, w2, t, s, below, above):
    return (_nm(w1), _nm(w2), _nm(t), _nm(s), _nm(below), _nm(above) if above else 0)


def prepare(pairs) -> None:
    """Solve, together, every pair of ``pairs`` ([(w1, w2, t, s, below, above)]) and the lines alone that
    ``kept`` asks for them (the extraction hands a layer's pairs over at once: one stacked solve instead of
    hundreds of small ones)."""
    keys = [_key(*p) for p in pairs]
    _solve_pairs(keys)
    _solve_singles([(w, t, b, u) for w1, w2, t, _s, b, u in keys for w in (w1, w2)])


def pair(w1: float, w2: float, t: float, s: float, below: float, above: float | None = None) -> tuple:
    """(coupling, line 1 to ground, line 2 to ground) per length, in units of the permittivity, of two lines
    w1 and w2 wide (m), t thick, s apart, ``below`` over a ground plane and ``above`` under a grounded
    conductor (None: none). Lengths are taken to the nm (a layout's grid is coarser)."""
    key = _key(w1, w2, t, s, below, above)
    if key not in _PAIRS:
        _solve_pairs([key])
    return _PAIRS[key]


def single(w: float, t: float, below: float, above: float | None = None) -> float:
    """Ground capacitance per length (in units of the permittivity) of one line alone, as ``pair``."""
    key = (_nm(w), _nm(t), _nm(below), _nm(above) if above else 0)
    if key not in _SINGLES:
        _solve_singles([key])
    return _SINGLES[key]


def kept(w1: float, w2: float, t: float, s: float, below: float, above: float | None = None) -> tuple:
    """The fraction of the facing edge's fringe each line keeps to ground beside the other: 1 - (its ground
    lost to the neighbour) / (one edge's fringe of the line alone), the fringe being the isolated line's
    ground less its plate terms, halved; both from the solve, clipped to 0 .. 1."""
    _c, g1, g2 = pair(w1, w2, t, s, below, above)
    out = []
    for w, g in ((w1, g1), (w2, g2)):
        alone = single(w, t, below, above)
        plate = w / below + (w / above if above else 0.0)
        edge = (alone - plate) / 2
        out.append(min(1.0, max(0.0, 1 - (alone - g) / edge)) if edge > 0 else 1.0)
    return tuple(out)
