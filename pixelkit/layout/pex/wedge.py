"""The field between sidewalls of one layer that see each other round a corner, with no facing
projection (so no lateral term in ``capacitance.py``): an end face beside another net's side face, a
corner beside a corner, a side face running on past another's end, two flush faces end to end.

**Perpendicular faces** (``right_wedges``; no constant). Two perpendicular sidewalls T high, of
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

from .cornerfield import _labelled
from .fringe import fringe
from .plane import covered_area, rects
from .topface import eps_fringe


def wedge(eps: float, t: float, angle: float, r_in, r_out):
    """Coupling (F) of two sidewalls t high at ``angle`` (rad) to each other whose faces span r_in ..
    r_out from the line their circular field lines centre on: ``eps ln(r_out / r_in) / angle`` per height
    (r_in, r_out may be arrays)."""
    import numpy as np
    return eps * np.log(r_out / r_in) / angle * t


def right_wedges(eps, t, r0, r1, q0, q1, pair, blocks):
    """Couplings (F) of pairs of perpendicular sidewalls t high spanning r0 .. r1 and q0 .. q1 from their common
    corner line, the field in the quarter plane between them. ``w = z^2`` opens the quarter plane to a half
    plane: the faces become coplanar strips [r0^2, r1^2] and [-q1^2, -q0^2] of its edge, a gap 2 g = r0^2 +
    q0^2 apart about m = (r0^2 - q0^2) / 2; half circles about m (the field of ``wedge`` at angle pi) join
    them from g out to the nearer strip end, ``eps ln(min(r1^2 - m, q1^2 + m) / g) / pi`` per height. Equal
    spans from the corner (r0 = q0) give the quarter circles' ``eps (2/pi) ln(min(r1, q1) / r0)``; faces
    that span no common distance from the corner (two corners facing diagonally) are joined too. A line
    that meets another conductor (``blocks``: boxes (x0, y0, x1, y1) in the quarter plane, x along the
    first face, y along the second) ends there: the radii |z^2 - m| its box spans are taken off.

    Arrays: r0 .. q1 (m) a pair of faces each; ``blocks`` rows (x0, y0, x1, y1) (m), row i in the quarter
    plane of pair ``pair[i]``."""
    import numpy as np
    m, g = (r0 * r0 - q0 * q0) / 2, (r0 * r0 + q0 * q0) / 2
    out = np.minimum(r1 * r1 - m, q1 * q1 + m)
    live = (g > 0) & (out > g)
    g, out = np.where(live, g, 1.0), np.where(live, out, 1.0)      # a pair that sees nothing: no radii
    b, p = blocks, pair
    keep = live[p] & (b[:, 0] ** 2 + b[:, 1] ** 2 - np.abs(m[p]) < out[p])  # boxes some line up to ``out`` can reach
    b, p = b[keep], p[keep]
    f = np.linspace(0.0, 1.0, 7)
    xs = (b[:, 0:1] + (b[:, 2:3] - b[:, 0:1]) * f)[:, :, None]     # 7 x 7 points of each box
    ys = (b[:, 1:2] + (b[:, 3:4] - b[:, 1:2]) * f)[:, None, :]
    rho = np.abs(xs * xs - ys * ys - m[p, None, None] + 2j * xs * ys).reshape(len(b), 49)
    lo, hi = np.maximum(rho.min(axis=1), g[p]), np.minimum(rho.max(axis=1), out[p])
    cut = hi > lo
    # each pair's spans [lo, hi] in a row (zeros after), in order of lo; the radii g .. out none covers
    order = np.lexsort((lo[cut], p[cut]))
    lo, hi, p = lo[cut][order], hi[cut][order], p[cut][order]
    col = np.arange(len(p)) - np.searchsorted(p, p)
    los, his = np.zeros((2, len(g), col.max() + 1 if len(p) else 0))
    los[p, col], his[p, col] = lo, hi
    reach = np.maximum.accumulate(np.concatenate([g[:, None], his], axis=1), axis=1)  # covered out to, before each
    free = np.log(np.maximum(np.concatenate([los, out[:, None]], axis=1) / reach, 1.0)).sum(axis=1)
    return eps * free / math.pi * t


def wedge_couplings(cpl, geo, stack, i, spent, stacking=None) -> None:
    """Add the field of layer ``i``'s sidewalls of different nets that face no other sidewall in
    projection (so have no lateral term) but see each other round a corner, to ``cpl``, and the fringe
    length (m) it takes from each edge to ``spent[(layer, net)]``: perpendicular faces (an end face
    beside another net's side face, a corner beside a corner; quarter circles about their corner line)
    and flush side faces of two shapes end to end across a gap s (half circles about the gap's middle,
    each face from s / 2 out). ``stacking`` (``stacks.Stacking``): flush faces whose nets both continue, flush,
    on the routing layer over / under are taller by half the gap to it (a pad stack's faces are one face);
    the faces round a corner are not (no FastCap2 structure checks them)."""
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
    lo_ext, hi_ext = _stacked(stacking, i, a, names)
    reach, dbu = cond.z / geo.dbu, geo.dbu
    boxes_of_layer = rects(layer)
    boxes, owner = _labelled({k: nets[name] for k, name in enumerate(names)})
    owner = np.array(owner)
    found = []                     # (net index, net index, coupling) arrays

    for axis in (0, 1):            # 0: vertical edges against horizontal ones; 1: the same turned by 90 degrees
        sv, sh = (a[:, 4] != 0, a[:, 5] != 0) if axis == 0 else (a[:, 5] != 0, a[:, 4] != 0)
        v, h = a[sv], a[sh]
        vlo, vhi = lo_ext[sv], hi_ext[sv]
        # (u, w): coordinates across / along v's edges; v's outward normal is along u
        vu, vw0, vw1, vn = (v[:, 0], np.minimum(v[:, 1], v[:, 3]), np.maximum(v[:, 1], v[:, 3]), v[:, 4]) if axis == 0 \
            else (v[:, 1], np.minimum(v[:, 0], v[:, 2]), np.maximum(v[:, 0], v[:, 2]), v[:, 5])
        hw, hu0, hu1, hn = (h[:, 1], np.minimum(h[:, 0], h[:, 2]), np.maximum(h[:, 0], h[:, 2]), h[:, 5]) if axis == 0 \
            else (h[:, 0], np.minimum(h[:, 1], h[:, 3]), np.maximum(h[:, 1], h[:, 3]), h[:, 4])
        if axis == 0:
            # quarter circles, every edge k of v (rows) against every edge j of h (columns): h beyond v's
            # plane on v's outward side, v's part on h's outward side; each face's part beyond the other's
            # plane (r along h's face, q along v's), out to the reach
            u, n, w0, w1 = vu[:, None], vn[:, None], vw0[:, None], vw1[:, None]
            r0 = np.maximum(np.where(n > 0, hu0 - u, u - hu1), 0.0)
            r1 = np.minimum(np.where(n > 0, hu1 - u, u - hu0), reach)
            q0 = np.maximum(np.where(hn > 0, w0 - hw, hw - w1), 0.0)
            q1 = np.minimum(np.where(hn > 0, w1 - hw, hw - w0), reach)
            kk, jj = np.nonzero((h[:, 6] != v[:, 6:7]) & (r1 > r0) & (q1 > q0) & (np.maximum(r0, q0) >= 1.0))
            # the other nets' boxes within the reach of each pair's quarter plane beyond (u, w), in its
            # coordinates (x along n from u, y along h's normal wn from w), clipped to it (pair, box)
            u, n, w, wn = vu[kk, None], vn[kk, None], hw[jj, None], hn[jj, None]
            u_far, w_far = u + n * reach, w + wn * reach
            pair, bi = np.nonzero((owner != v[kk, 6:7]) & (owner != h[jj, 6:7])
                                  & (boxes[:, 2] > np.minimum(u, u_far)) & (boxes[:, 0] < np.maximum(u, u_far))
                                  & (boxes[:, 3] > np.minimum(w, w_far)) & (boxes[:, 1] < np.maximum(w, w_far)))
            u, n, w, wn, bx = u[pair, 0], n[pair, 0], w[pair, 0], wn[pair, 0], boxes[bi]
            x0, x1 = (bx[:, 0] - u) * n, (bx[:, 2] - u) * n
            y0, y1 = (bx[:, 1] - w) * wn, (bx[:, 3] - w) * wn
            blocks = np.stack([np.maximum(np.minimum(x0, x1), 0), np.maximum(np.minimum(y0, y1), 0),
                               np.maximum(x0, x1), np.maximum(y0, y1)], axis=1)
            inside = (blocks[:, 2] > blocks[:, 0]) & (blocks[:, 3] > blocks[:, 1])
            args = (stack.eps_band(cond.z, cond.top), cond.thickness, *(x[kk, jj] * dbu for x in (r0, r1, q0, q1)))
            pair, blocks = pair[inside], blocks[inside] * dbu
            c = right_wedges(*args, pair, blocks)
            found.append((v[kk, 6], h[jj, 6], c))
        # half circles: edge k against another edge j > k of the same orientation, flush with it (within
        # half the gap), end to end across a gap s along them
        gap = np.maximum(vw0 - vw1[:, None], vw0[:, None] - vw1)
        kk, jj = np.nonzero(np.triu((v[:, 6] != v[:, 6:7]) & (vn == vn[:, None]) & (gap > 0)
                                    & (np.abs(vu - vu[:, None]) <= gap / 2) & (gap < 2 * reach), 1))
        s, n = gap[kk, jj], vn[kk]
        lo, hi = s / 2, np.minimum(s / 2 + np.minimum(vw1[kk] - vw0[kk], vw1[jj] - vw0[jj]), reach)
        mid = (np.minimum(vw1[kk], vw1[jj]) + np.maximum(vw0[kk], vw0[jj])) / 2
        plane = np.where(n > 0, np.maximum(vu[kk], vu[jj]), np.minimum(vu[kk], vu[jj]))
        # the field's square beside the gap (dbu, truncated to integers); the part other shapes cover is taken off
        u0, u1, w0, w1 = (np.trunc(x) for x in (plane, plane + n * hi, mid - hi, mid + hi))
        x0, y0, x1, y1 = (u0, w0, u1, w1) if axis == 0 else (w0, u0, w1, u1)
        x0, x1, y0, y1 = np.minimum(x0, x1), np.maximum(x0, x1), np.minimum(y0, y1), np.maximum(y0, y1)
        area = (x1 - x0) * (y1 - y0)
        keep = (hi > lo) & (area > 0)
        covered = covered_area(boxes_of_layer, np.stack([x0[keep], y0[keep], x1[keep], y1[keep]], axis=1))
        area = area[keep]
        c = wedge(stack.eps_band(cond.z, cond.top), cond.thickness, math.pi, lo[keep] * dbu, hi[keep] * dbu) * (1 - covered / area) \
            * _taller(cond.thickness, vlo[kk[keep]], vlo[jj[keep]], vhi[kk[keep]], vhi[jj[keep]])
        found.append((v[kk[keep], 6], v[jj[keep], 6], c))

    a_net, b_net, c = (np.concatenate(x) for x in zip(*found))
    pairs = len(names) * a_net.astype(int) + b_net.astype(int)
    total = np.bincount(pairs[c > 0], weights=c[c > 0], minlength=len(names) ** 2)
    for key in np.nonzero(total)[0]:
        _couple(cpl, spent, stack, cond, names[key // len(names)], names[key % len(names)], total[key])


def _stacked(stacking, i, a, names):
    """The height (m) each face (rows of ``a``: x1, y1, x2, y2, outward normal, net index) gains under and over
    it where its net continues flush on the routing layer there (``stacks.Stacking``): two arrays."""
    import numpy as np
    if stacking is None:
        return np.zeros(len(a)), np.zeros(len(a))
    mids = np.stack([(a[:, 0] + a[:, 2]) / 2, (a[:, 1] + a[:, 3]) / 2], axis=1)
    down, up = stacking.runs(i, [names[int(k)] for k in a[:, 6]], mids, a[:, 4:6])
    z = np.zeros(len(a))
    return stacking.extension(i, down, z), stacking.extension(i, z, up)


def _taller(t, lo_a, lo_b, hi_a, hi_b):
    """A pair of faces' height over the layer's thickness: both faces' nets stacked under (over) them add the
    smaller of their gains there."""
    import numpy as np
    return (t + np.minimum(lo_a, lo_b) + np.minimum(hi_a, hi_b)) / t


def _couple(cpl, spent, stack, cond, a_net, b_net, c):
    """Add ``c`` between the two nets, half of it taken from each one's fringe on ``cond``."""
    cpl.add(a_net, b_net, c)
    f = fringe(eps_fringe(stack, cond.z, cond.thickness, cond.z), cond.thickness, cond.z)
    spent[(cond.name, a_net)] += c / 2 / f
    spent[(cond.name, b_net)] += c / 2 / f
