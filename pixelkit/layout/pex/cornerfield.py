"""The corner fields the 2.5D terms of ``capacitance.py`` leave out: between an edge and a conductor
of a higher layer beside it (offset in plan), and between sidewalls of one layer that see each other
round a corner.

The 2.5D terms send an edge's field down (the fringe, to what lies under the strip beside it), up
only where another net's conductor lies over that strip (shared by area), and sideways only to a
same-layer edge facing it in projection (Chern et al.'s lateral term). Against FastCap2 that misses
most of the coupling of conductors whose edges face each other a short way apart in plan on
different layers: a metal1 line 0.23 um wide and a metal2 line 0.38 um wide beside it (6 um long,
over the substrate) couple by 48.0 / 43.6 / 37.8 / 28.2 aF/um with their facing edges 0 / 0.23 /
0.5 / 1.0 um apart in plan, those terms alone give 17.2 / 17.2 / 17.2 / 14.3; and it misses the field
between an edge's end face and another net's side face beside it, which no projection pairs. On FD
(a metal1 node of 0.88 um2 with edges of 0.2 - 0.5 um, metal1 - 3 lines a few tenths of a um beside
them) those are most of its row lines' and supplies' coupling (docs/post-layout.md).

**Edge to an upper conductor beside it** (``corner``; derived here). A lower conductor A (top at
z_A + T_A) and an upper one B (bottom z_B, thickness T_B), g = z_B - z_A - T_A apart in height, with
facing edges d apart in plan (d = 0 also where B's edge stands over A near A's facing edge). Two
field regions lie between them: B's sidewall down to A's top face, and A's sidewall up to B's
underside. A field line from a sidewall at height y over the plane of a face runs a quarter circle of
radius y and then straight across the gap g (length g + pi y / 2), so a sidewall of height T over a
face at gap g couples by ``eps (2/pi) ln(1 + pi T / (2 g))`` per length. Seen from A's edge, B's edge
at d subtends ``(2/pi) atan((g + T_B) / d)`` of the quarter plane above and outside it (1 at d = 0).
Per facing length::

    c = KAPPA eps (2/pi) ln(1 + pi T_B / (2 g)) (2/pi) atan((g + T_B) / d)

The construction gives KAPPA = 2 (the two sidewalls, T_A = T_B here); 1.6 was set with FastCap2 on
the metal1 / metal2 pair above (the kit then: 45.9 / 42.1 / 38.3 / 30.2 aF/um, -4 .. +7 %, the two
lines' ground within 4 %) and checked on a metal1 / metal3 pair (g = 1.75 um, not used in the
setting: FastCap2 21.2 / 20.6 / 19.7 / 17.5 aF/um, the kit -6 / -9 / -10 / -15 %;
``tests/test_extraction.py``). Conductors between the two heights intercept the field: the part of
the plan gap between the edges covered by a conductor of A's layer or of a layer between (each grown
by half its height over A's top: the lines from A's corner spread as they rise) is taken off. Edges
further apart in plan than A's height over the substrate (the fringe strip's width) are not coupled.

**Sidewalls round a corner on one layer** (``wedge``; no constant). Two perpendicular sidewalls of
different nets (an end face beside another net's side face, a corner beside a corner), whose faces
span r_in .. r_out from their common corner line, couple along circular field lines (quarter circles
about that line) by ``eps (2/pi) ln(r_out / r_in)`` per height T, the exact field of a right-angle
wedge; two flush side faces of shapes end to end across a gap s, by half circles about the gap's
middle, ``eps (1/pi) ln(r_out / (s / 2))`` per height. The part of the field's square beside the
corner covered by other shapes of the layer is taken off; r_out is at most the fringe strip's width.

Charge: each of these fields was counted by the 2.5D terms as fringe of the edges bounding it (going
mostly to the substrate), so a coupling c takes half its length-equivalent from each edge's fringe:
``c / 2 / fringe(T, z)`` of its fringe length (``fringe.fringe``).
"""
from __future__ import annotations

import math

from .fringe import fringe

KAPPA = 1.6    # the two sidewall-to-face regions (2 by the construction), set on a metal1 / metal2 pair


def corner(eps: float, t_b: float, g: float, d: float) -> float:
    """Coupling per length (F/m) of an edge and an upper conductor's edge g over its top and d beside it in plan."""
    ang = 1.0 if d <= 0 else (2 / math.pi) * math.atan((g + t_b) / d)
    return KAPPA * eps * (2 / math.pi) * math.log(1 + math.pi * t_b / (2 * g)) * ang


def corner_couplings(cpl, geo, stack, i, spent) -> None:
    """Add the corner field of layer ``i``'s edges to every higher layer's conductors of other nets to
    ``cpl``, and the fringe length (m) it takes from each edge to ``spent[(layer, net)]``."""
    import klayout.db as kdb
    cond = stack.conductors[i]
    nets = geo.wires.get(cond.name, {})
    if not nets:
        return
    dbu, eps = geo.dbu, stack.eps
    top = cond.top
    reach = int(round(cond.z / dbu))
    lower = kdb.Region()
    for r in nets.values():
        lower += r
    lower.merge()
    inner = lower.sized(-1)            # flush edges (d = 0) are then 1 dbu apart: the separation check finds them
    own = _labelled(nets)
    blocking = [(top, lower)]          # (height, conductors) between A's top and the upper layer
    for cb in stack.conductors[i + 1:]:
        up = geo.wires.get(cb.name, {})
        if not up:
            continue
        upper = kdb.Region()
        for r in up.values():
            upper += r
        upper.merge()
        g = cb.z - top
        block = kdb.Region()
        for zk, rk in blocking:
            grow = int(round((zk - top) / 2 / dbu))
            block += rk.sized(grow) if grow > 0 else rk
        rects = _rects(block)
        theirs = _labelled(up)
        apart = inner.separation_check(upper, reach, False, kdb.Region.Projection, None, None, None, True)
        over = lower.overlap_check(upper, reach, False, kdb.Region.Projection, None, None, None, True)
        for ep, flush in [(e, False) for e in apart.each()] + [(e, True) for e in over.each()]:
            a_net, b_net = _net_at(own, ep.first), _net_at(theirs, ep.second)
            if a_net is None or b_net is None or a_net == b_net:
                continue
            d = 0.0 if flush else ep.distance() * dbu
            gap = ep.polygon(0).bbox()
            free = 1.0 if flush or gap.area() == 0 else 1 - _covered(rects, gap) / gap.area()
            c = corner(eps, cb.thickness, g, d) * free * (ep.first.length() + ep.second.length()) / 2 * dbu
            if c <= 0:
                continue
            cpl.add(a_net, b_net, c)
            spent[(cond.name, a_net)] += c / 2 / fringe(eps, cond.thickness, cond.z)
            spent[(cb.name, b_net)] += c / 2 / fringe(eps, cb.thickness, cb.z)
        blocking.append((cb.z, upper))


def _rects(region):
    """The merged ``region`` as non-overlapping boxes (its trapezoids' boxes: exact on a Manhattan layer),
    an array of (left, bottom, right, top)."""
    import klayout.db as kdb
    import numpy as np
    boxes = [(b.left, b.bottom, b.right, b.top) for p in region.merged().each()
             for b in (t.bbox() for t in p.decompose_trapezoids(kdb.Polygon.TD_htrapezoids))]
    return np.array(boxes, dtype=float).reshape(-1, 4)


def _covered(rects, box) -> float:
    """Area (dbu2) of ``box`` that ``rects`` (``_rects``) cover."""
    import numpy as np
    w = np.clip(np.minimum(rects[:, 2], box.right) - np.maximum(rects[:, 0], box.left), 0, None)
    h = np.clip(np.minimum(rects[:, 3], box.top) - np.maximum(rects[:, 1], box.bottom), 0, None)
    return float(np.sum(w * h))


def _labelled(nets):
    """Every net's shapes as boxes (``_rects``) and the net of each box: (boxes, [net])."""
    import numpy as np
    parts = [(_rects(reg), net) for net, reg in nets.items()]
    boxes = np.concatenate([b for b, _ in parts]) if parts else np.zeros((0, 4))
    return boxes, [net for b, net in parts for _ in range(len(b))]


def _net_at(labelled, edge):
    """The net whose shape carries ``edge`` (a box of it within 2 dbu of the edge's midpoint)."""
    import numpy as np
    boxes, names = labelled
    x, y = (edge.p1.x + edge.p2.x) / 2, (edge.p1.y + edge.p2.y) / 2
    hit = np.nonzero((boxes[:, 0] - 2 <= x) & (x <= boxes[:, 2] + 2) & (boxes[:, 1] - 2 <= y) & (y <= boxes[:, 3] + 2))[0]
    return names[hit[0]] if len(hit) else None


def wedge(eps: float, t: float, angle: float, r_in: float, r_out: float) -> float:
    """Coupling (F) of two sidewalls t high at ``angle`` (rad) to each other whose faces span r_in ..
    r_out from the line their circular field lines centre on: ``eps ln(r_out / r_in) / angle`` per height."""
    return eps * math.log(r_out / r_in) / angle * t


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

    def add(a_net, b_net, angle, lo, hi, box):
        if box.area() == 0:
            return
        free = 1 - _covered(rects, box) / box.area()
        c = wedge(stack.eps, cond.thickness, angle, lo * geo.dbu, hi * geo.dbu) * free
        if c > 0:
            _couple(cpl, spent, stack, cond, names[int(a_net)], names[int(b_net)], c)

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
                lo = np.maximum(np.maximum(r0, q0), 1.0)
                hi = np.minimum(np.minimum(r1, q1), reach)
                for j in np.nonzero((h[:, 6] != net) & (r0 > 0) & (hi > lo))[0]:
                    add(net, h[j, 6], math.pi / 2, lo[j], hi[j],
                        kdb.Box(int(u), int(hw[j]), int(u + n * hi[j]), int(hw[j] + hn[j] * hi[j])))
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
