"""The field between sidewalls of one layer that see each other round a corner, with no facing
projection (so no lateral term in ``capacitance.py``): an end face beside another net's side face, a
corner beside a corner, a side face running on past another's end, two flush faces end to end.

**Perpendicular faces** (``right_wedge``; no constant). Two perpendicular sidewalls T high, of
different nets, meet (extended) at a corner line; the part of each beyond the other's plane spans
r0 .. r1 and q0 .. q1 from that line (a face that runs on past the other's plane counts from the
line: r0 = 0). The field between them fills the quarter plane they bound. ``w = z^2`` opens it to a
half plane and the two faces become coplanar strips of its edge, [r0^2, r1^2] and [-q1^2, -q0^2], a
gap 2 g = r0^2 + q0^2 apart about m = (r0^2 - q0^2) / 2. The field of two coplanar strips across a
gap runs in half circles about the gap's middle (the flush case below, now in the w plane), from g
out to the nearer strip's end, so per height::

    c = eps ln(min(r1^2 - m, q1^2 + m) / g) / pi

For faces at equal distances from the corner (r0 = q0) these are the quarter circles about the
corner line, ``eps (2/pi) ln(min(r1, q1) / r0)`` (the kit's term before); faces that span no common
distance (two corners facing diagonally: TG's metal1 pad 0.98 um beside and 0.13 um below FD's foot)
and faces that run on past the other's plane (the photodiode's metal1 line past the end of FD's foot,
under FD's stem) were not coupled at all, and the term was not symmetric (a vertical face running past
a horizontal one's plane counted, a horizontal one past a vertical one's did not). A line that meets
a conductor of a third net in the quarter plane ends there: the radii |z^2 - m| of the w-plane half
circles that cross its box are taken off (a shape between the two faces cuts the lines that pass it,
not a share of the field by its area). Faces are taken out to the fringe strip's width (the layer's
height over the substrate: further out the field goes down).

Against FastCap2, the secondary's FD with its eight metal1 neighbours alone (the other layers and
the diffusions left out; ``tests/test_extraction.py``), quarter circles over the faces' common span
(about the term before) -> this term (FastCap2), aF: ground 214.2 -> 192.7 (199.2), RST 29.8 -> 37.8
(38.2), the photodiode line 53.2 -> 62.9 (68.3), VDD 20.0 -> 25.5 (27.1), VRST 98.0 -> 111.3 (107.2),
TG's pad 0 -> 5.0 (11.3; diagonal corners stay low).

**Flush faces** (``wedge`` at angle pi; no constant): two side faces of shapes end to end across a gap
s, by half circles about the gap's middle, ``eps (1/pi) ln(r_out / (s / 2))`` per height; the part of
the field's square beside the gap covered by other shapes of the layer is taken off.

Charge: each of these fields was counted by the 2.5D terms as fringe of the edges bounding it (going
mostly to the substrate), so a coupling c takes half its length-equivalent from each edge's fringe:
``c / 2 / fringe(T, z)`` of its fringe length (``fringe.fringe``).
"""
from __future__ import annotations

import math

from .cornerfield import _covered, _labelled, _rects
from .fringe import fringe


def wedge(eps: float, t: float, angle: float, r_in: float, r_out: float) -> float:
    """Coupling (F) of two sidewalls t high at ``angle`` (rad) to each other whose faces span r_in ..
    r_out from the line their circular field lines centre on: ``eps ln(r_out / r_in) / angle`` per height."""
    return eps * math.log(r_out / r_in) / angle * t


def right_wedge(eps: float, t: float, r0: float, r1: float, q0: float, q1: float, blocks=()) -> float:
    """Coupling (F) of two perpendicular sidewalls t high spanning r0 .. r1 and q0 .. q1 from their common
    corner line, the field in the quarter plane between them. ``w = z^2`` opens the quarter plane to a half
    plane: the faces become coplanar strips [r0^2, r1^2] and [-q1^2, -q0^2] of its edge, a gap 2 g = r0^2 +
    q0^2 apart about m = (r0^2 - q0^2) / 2; half circles about m (the field of ``wedge`` at angle pi) join
    them from g out to the nearer strip end, ``eps ln(min(r1^2 - m, q1^2 + m) / g) / pi`` per height. Equal
    spans from the corner (r0 = q0) give the quarter circles' ``eps (2/pi) ln(min(r1, q1) / r0)``; faces
    that span no common distance from the corner (two corners facing diagonally) are joined too. A line
    that meets another conductor (``blocks``: boxes (x0, y0, x1, y1) in the quarter plane, x along the
    first face, y along the second) ends there: the radii |z^2 - m| its box spans are taken off."""
    import numpy as np
    m, g = (r0 * r0 - q0 * q0) / 2, (r0 * r0 + q0 * q0) / 2
    out = min(r1 * r1 - m, q1 * q1 + m)
    if g <= 0 or out <= g:
        return 0.0
    cut = []
    b = np.asarray(blocks, dtype=float).reshape(-1, 4)
    if len(b):
        b = b[b[:, 0] ** 2 + b[:, 1] ** 2 - abs(m) < out]      # boxes some line up to ``out`` can reach
    if len(b):
        f = np.linspace(0.0, 1.0, 7)
        xs = (b[:, 0:1] + (b[:, 2:3] - b[:, 0:1]) * f)[:, :, None]     # 7 x 7 points of each box
        ys = (b[:, 1:2] + (b[:, 3:4] - b[:, 1:2]) * f)[:, None, :]
        rho = np.abs(xs * xs - ys * ys - m + 2j * xs * ys).reshape(len(b), -1)
        lo, hi = np.maximum(rho.min(axis=1), g), np.minimum(rho.max(axis=1), out)
        cut = sorted(zip(lo[hi > lo].tolist(), hi[hi > lo].tolist()))
    free, reach = 0.0, g
    for lo, hi in cut:
        if lo > reach:
            free += math.log(lo / reach)
        reach = max(reach, hi)
    free += math.log(out / reach) if out > reach else 0.0
    return eps * free / math.pi * t


def wedge_couplings(cpl, geo, stack, i, spent) -> None:
    """Add the field of layer ``i``'s sidewalls of different nets that face no other sidewall in
    projection (so have no lateral term) but see each other round a corner, to ``cpl``, and the fringe
    length (m) it takes from each edge to ``spent[(layer, net)]``: perpendicular faces (an end face
    beside another net's side face, a corner beside a corner; quarter circles about their corner line)
    and flush side faces of two shapes end to end across a gap s (half circles about the gap's middle,
    each face from s / 2 out)."""
    import klayout.db as kdb
    import numpy as np
    cond = stack.conductors[i]
    nets = geo.wires.get(cond.name, {})
    if len(nets) < 2:
        return
    names = sorted(nets)
    layer = kdb.Region()
    rows = []                      # x1, y1, x2, y2, outward normal x, y, net index
    for k, net in enumerate(names):
        reg = nets[net].merged()
        layer += reg
        for e in reg.edges().each():
            dx, dy = e.p2.x - e.p1.x, e.p2.y - e.p1.y
            if dx == 0 or dy == 0:
                rows.append((e.p1.x, e.p1.y, e.p2.x, e.p2.y, -np.sign(dy), np.sign(dx), k))
    if not rows:
        return
    a = np.array(rows, dtype=float)
    reach = cond.z / geo.dbu
    rects = _rects(layer)
    boxes, owner = _labelled({k: nets[name] for k, name in enumerate(names)})
    owner = np.array(owner)

    def near(u, n):
        """The boxes (and their nets) within the reach of the plane x = u on its side n."""
        lo_u, hi_u = sorted((u, u + n * reach))
        sel = (boxes[:, 2] > lo_u) & (boxes[:, 0] < hi_u)
        return boxes[sel], owner[sel]

    def blockers(cand, u, n, w, wn, a_net, b_net):
        """The other nets' boxes of ``cand`` (``near``) in the quarter plane beyond (u, w) (x along n from
        u, y along wn from w), in those local coordinates (m), clipped to it: array of (x0, y0, x1, y1)."""
        bx, own = cand
        lo_w, hi_w = sorted((w, w + wn * reach))
        bx = bx[(own != a_net) & (own != b_net) & (bx[:, 3] > lo_w) & (bx[:, 1] < hi_w)]
        x0, x1 = (bx[:, 0] - u) * n, (bx[:, 2] - u) * n
        y0, y1 = (bx[:, 1] - w) * wn, (bx[:, 3] - w) * wn
        out = np.stack([np.maximum(np.minimum(x0, x1), 0), np.maximum(np.minimum(y0, y1), 0),
                        np.maximum(x0, x1), np.maximum(y0, y1)], axis=1)
        return out[(out[:, 2] > out[:, 0]) & (out[:, 3] > out[:, 1])] * geo.dbu

    def add_c(a_net, b_net, c, box):
        if box.area() == 0:
            return
        c *= 1 - _covered(rects, box) / box.area()
        if c > 0:
            _couple(cpl, spent, stack, cond, names[int(a_net)], names[int(b_net)], c)

    def add(a_net, b_net, angle, lo, hi, box):
        add_c(a_net, b_net, wedge(stack.eps, cond.thickness, angle, lo * geo.dbu, hi * geo.dbu), box)

    for axis in (0, 1):            # 0: vertical edges against horizontal ones; 1: the same turned by 90 degrees
        v = a[a[:, 4] != 0] if axis == 0 else a[a[:, 5] != 0]
        h = a[a[:, 5] != 0] if axis == 0 else a[a[:, 4] != 0]
        # (u, w): coordinates across / along v's edges; v's outward normal is along u
        vu, vw0, vw1, vn = (v[:, 0], np.minimum(v[:, 1], v[:, 3]), np.maximum(v[:, 1], v[:, 3]), v[:, 4]) if axis == 0 \
            else (v[:, 1], np.minimum(v[:, 0], v[:, 2]), np.maximum(v[:, 0], v[:, 2]), v[:, 5])
        hw, hu0, hu1, hn = (h[:, 1], np.minimum(h[:, 0], h[:, 2]), np.maximum(h[:, 0], h[:, 2]), h[:, 5]) if axis == 0 \
            else (h[:, 0], np.minimum(h[:, 1], h[:, 3]), np.maximum(h[:, 1], h[:, 3]), h[:, 4])
        for k in range(len(v)):
            u, w0, w1, n, net = vu[k], vw0[k], vw1[k], vn[k], v[k, 6]
            if axis == 0:
                # quarter circles: h beyond v's plane on v's outward side, v's part on h's outward side
                r0 = np.where(n > 0, hu0 - u, u - hu1)
                r1 = np.where(n > 0, hu1 - u, u - hu0)
                q0 = np.where(hn > 0, w0 - hw, hw - w1)
                q1 = np.where(hn > 0, w1 - hw, hw - w0)
                # each face's part beyond the other's plane (r along h's face, q along v's), out to the reach
                r0, q0 = np.maximum(r0, 0.0), np.maximum(q0, 0.0)
                r1, q1 = np.minimum(r1, reach), np.minimum(q1, reach)
                ok = (h[:, 6] != net) & (r1 > r0) & (q1 > q0) & (np.maximum(r0, q0) >= 1.0)
                cand = near(u, n)
                for j in np.nonzero(ok)[0]:
                    c = right_wedge(stack.eps, cond.thickness, r0[j] * geo.dbu, r1[j] * geo.dbu,
                                    q0[j] * geo.dbu, q1[j] * geo.dbu, blockers(cand, u, n, hw[j], hn[j], net, h[j, 6]))
                    if c > 0:
                        _couple(cpl, spent, stack, cond, names[int(net)], names[int(h[j, 6])], c)
            # half circles: another edge of the same orientation, flush with this one (within half the
            # gap), end to end across a gap along them
            same = v[:, 6] != net
            gap = np.maximum(vw0 - w1, w0 - vw1)
            flush = same & (vn == n) & (gap > 0) & (np.abs(vu - u) <= gap / 2) & (gap < 2 * reach)
            for j in np.nonzero(flush & (np.arange(len(v)) > k))[0]:
                s = gap[j]
                lo, hi = s / 2, min(s / 2 + min(w1 - w0, vw1[j] - vw0[j]), reach)
                mid = (min(w1, vw1[j]) + max(w0, vw0[j])) / 2
                plane = max(u, vu[j]) if n > 0 else min(u, vu[j])
                box = kdb.Box(int(plane), int(mid - hi), int(plane + n * hi), int(mid + hi)) if axis == 0 \
                    else kdb.Box(int(mid - hi), int(plane), int(mid + hi), int(plane + n * hi))
                if hi > lo:
                    add(net, v[j, 6], math.pi, lo, hi, box)


def _couple(cpl, spent, stack, cond, a_net, b_net, c):
    """Add ``c`` between the two nets, half of it taken from each one's fringe on ``cond``."""
    cpl.add(a_net, b_net, c)
    f = fringe(stack.eps, cond.thickness, cond.z)
    spent[(cond.name, a_net)] += c / 2 / f
    spent[(cond.name, b_net)] += c / 2 / f
