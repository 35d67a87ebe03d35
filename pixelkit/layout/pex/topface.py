"""The top face's share of an edge's fringe, and what a conductor of another net over that face takes.

The fringe of ``fringe.fringe`` is an isolated line's: the charge an edge adds beyond the plate
term, on its bottom face near the edge, its sidewall and its top face, whose field wraps round the
edge down to the plane beside it. Where a conductor of another net lies over the top face near the
edge (a MIM capacitor's top plate 42 nm over its bottom plate, set back 0.6 um from its edge; a line
crossing over another), the top face's field from under it ends on that conductor instead.

How much of the fringe each strip of the top face carries: the edge of a thin conductor h over a
ground plane (the half-plane; conformal map ``z = (h/pi)(w + 1 + ln w)``, potential ``arg(w) / pi``).
A point of the top face x from the edge is ``w = -u`` with ``u - 1 - ln u = pi x / h`` (u >= 1), of
the bottom face ``1 - u + ln u = -pi x / h`` (u <= 1); the flux between two points of a face is
``(eps / pi) |ln(u2 / u1)|``. Within the fringe strip's width h of the edge, the top face carries
``(eps / pi) ln u_top(h)`` = 0.566 eps and the bottom face ``(eps / pi)(1 - u_bottom(h))`` = 0.313 eps
beyond its plate term: 0.879 eps per edge, the kit's fringe of a metal4 edge (T / h = 0.12) being
0.87 eps. The top face's strip from x1 to x2 carries ``ln(u(x2) / u(x1)) / TOTAL`` of the edge's
fringe (TOTAL the two faces' 2.76). A cover g over the face takes that share times
``h / (g + h)`` (the split ``capacitance._fringe_band`` gives a conductor over the strip beside the
edge: the nearer plane takes more), shared by the strip's parts under it by area; the fringe length
it takes couples the edge's net to the cover's. A conductor of the edge's own net over the face is
not a cover here (that field stays within the net). No constant. On C11's bottom plate (metal4,
22.7 x 13.0 um, 4.68 um up) FastCap2 finds 4.627 fF to ground with the plate alone and 3.911 fF
with the top plate over it (0.716 fF less); the kit, isolated fringe, 4.440 fF either way, with the
covers 3.831 fF (-2.0 %; 0.61 fF less); with the metal5 strap too FastCap2 3.616, the kit 4.362 ->
3.655 fF. The drawn C11 (docs/post-layout.md): bottom plate +19.4 -> +3.6 % against FastCap2.
"""
from __future__ import annotations

import functools
import math

SLICES = 6    # strips of the top face within the fringe strip's width of the edge


def _u_top(a: float) -> float:
    """u >= 1 with u - 1 - ln u = a (a >= 0), by bisection."""
    lo, hi = 1.0, 2.0 + 2 * a
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if mid - 1 - math.log(mid) < a else (lo, mid)
    return (lo + hi) / 2


def _u_bottom(a: float) -> float:
    """u in (0, 1] with 1 - u + ln u = -a (a >= 0), by bisection."""
    lo, hi = 1e-300, 1.0
    for _ in range(200):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if 1 - mid + math.log(mid) < -a else (lo, mid)
    return (lo + hi) / 2


TOTAL = math.log(_u_top(math.pi)) + 1 - _u_bottom(math.pi)    # both faces' fringe within h, in eps / pi
SHARES = [math.log(_u_top(math.pi * (k + 1) / SLICES) / _u_top(math.pi * k / SLICES)) / TOTAL
          for k in range(SLICES)]    # each strip's share of the edge's fringe, the edge outward first


def covered_top(net, reg, above, z, t, dbu):
    """[(cover net, its layer, fringe length m)] the conductors of other nets over the top face of ``net``'s
    ``reg`` (at height z, t thick; ``above``: ``capacitance._above``) take from its edges' fringe."""
    width = max(SLICES, int(round(z / dbu)))     # the fringe strip's width h, in dbu
    out = {}
    for k, share in enumerate(SHARES):
        a0, a1 = width * k // SLICES, width * (k + 1) // SLICES
        strip = (reg.sized(-a0) if a0 else reg) - reg.sized(-a1)
        if strip.is_empty():
            continue
        rest = strip
        for plane in above:
            union = plane.near(rest)
            hit = rest & union
            if hit.is_empty():
                continue
            g = plane.z - (z + t)
            for m, cover in plane.nets_near(hit):
                if m == net:
                    continue
                area = (hit & cover).area()
                if area:
                    out[(m, plane.name)] = out.get((m, plane.name), 0.0) + area / (a1 - a0) * dbu * share * z / (g + z)
            rest = rest - union
    return [(m, lay, v) for (m, lay), v in sorted(out.items())]


@functools.lru_cache(maxsize=1 << 14)    # a layer's edges ask the same few gaps
def eps_fringe(stack, z: float, t: float, h: float) -> float:
    """The permittivity of the fringe of an edge of a conductor z .. z + t over a plane h below it, in a
    layered stack (``Stack.eps_gap``: across the layers in series). The bottom face's share runs down
    through the gap; the top face's, strip by strip (SHARES, within h of the edge), along field lines that
    leave the face x from the edge and rise about x over it before wrapping round the edge: each strip
    through the layers from the top face to x above it. In a uniform stack, the stack's permittivity.
    No constant: the shares are the half-plane's."""
    if not stack.dielectrics:
        return stack.eps
    top = z + t
    up = sum(sh * stack.eps_gap(top, top + h * (k + 0.5) / SLICES) for k, sh in enumerate(SHARES))
    return up + (1 - sum(SHARES)) * stack.eps_gap(z - h, z)
