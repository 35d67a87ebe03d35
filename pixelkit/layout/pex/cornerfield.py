"""The corner field the 2.5D terms of ``capacitance.py`` leave out between an edge and a conductor of a
higher layer beside it (offset in plan); the same-layer field round a corner is ``wedge.py``'s.

The 2.5D terms send an edge's field down (the fringe, to what lies under the strip beside it), up
only where another net's conductor lies over that strip (shared by area), and sideways only to a
same-layer edge facing it in projection (Chern et al.'s lateral term). Against FastCap2 that misses
most of the coupling of conductors whose edges face each other a short way apart in plan on
different layers: a metal1 line 0.23 um wide and a metal2 line 0.38 um wide beside it (6 um long,
over the substrate) couple by 48.0 / 43.6 / 37.8 / 28.2 aF/um with their facing edges 0 / 0.23 /
0.5 / 1.0 um apart in plan, those terms alone give 17.2 / 17.2 / 17.2 / 14.3. On FD (a metal1 node
of 0.88 um2 with edges of 0.2 - 0.5 um, metal1 - 3 lines a few tenths of a um beside them) that is
most of its row lines' and supplies' coupling (docs/post-layout.md).

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

**Where the lines land** (``_landing_free``; no constant). The quarter circles of the first region
leave B's sidewall towards A and land on A's top face within g + T_B of B's edge (their largest
radius plus the gap); those of the second leave A's sidewall and land on B's underside within
g + T_A of A's edge. A conductor of a third net over that part of A's top face (on a layer above A, up
to B's own: a line of B's layer beside B, over A, faces B's sidewall first) or under that part of B's
underside (on a layer between) takes the lines that would land there. So each region keeps the
uncovered fraction of its landing strip, and the two regions count half each: ``c`` times the mean
of the two fractions. A metal1 block (3 x 0.6 um) with a metal3 line beside its long edge (d = 0.23 um)
and a third net's metal3 line over its top face ending 0.045 um short of that edge: FastCap2 47.5 aF
between the block and the line beside it, the kit 47.2 (59.4 without this, +25 %;
``tests/test_extraction.py``). The drawn case: the secondary's FD foot under TG's metal3 line with
RST's metal3 line 0.23 um beside it (RST to FD +19 -> +13 %), the primary's FD foot half under
VPDR's metal2 with TG's metal2 line 0.98 um beside it (TG to FD +18 -> +10 %).

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
    covers = {}                        # net -> Region: the conductors of the layers above A so far
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
        covers_under = dict(covers)            # other conductors between A's top and B's bottom, by net
        for n, r in up.items():
            covers[n] = covers[n] + r if n in covers else r.dup()
        covers_top = covers                    # ... and on B's layer
        others = {}                            # (A's net, B's net) -> the two covers of the other nets
        apart = inner.separation_check(upper, reach, False, kdb.Region.Projection, None, None, None, True)
        over = lower.overlap_check(upper, reach, False, kdb.Region.Projection, None, None, None, True)
        for ep, flush in [(e, False) for e in apart.each()] + [(e, True) for e in over.each()]:
            a_net, b_net = _net_at(own, ep.first), _net_at(theirs, ep.second)
            if a_net is None or b_net is None or a_net == b_net:
                continue
            d = 0.0 if flush else ep.distance() * dbu
            gap = ep.polygon(0).bbox()
            free = 1.0 if flush or gap.area() == 0 else 1 - _covered(rects, gap) / gap.area()
            if (a_net, b_net) not in others:
                others[(a_net, b_net)] = (_others(covers_top, a_net, b_net), _others(covers_under, a_net, b_net))
            free *= _landing_free(ep, flush, nets[a_net], up[b_net], g + cb.thickness, g + cond.thickness, dbu,
                                  *others[(a_net, b_net)])
            c = corner(eps, cb.thickness, g, d) * free * (ep.first.length() + ep.second.length()) / 2 * dbu
            if c <= 0:
                continue
            cpl.add(a_net, b_net, c)
            spent[(cond.name, a_net)] += c / 2 / fringe(eps, cond.thickness, cond.z)
            spent[(cb.name, b_net)] += c / 2 / fringe(eps, cb.thickness, cb.z)
        blocking.append((cb.z, upper))


def _others(by_net, a_net, b_net):
    """The conductors of ``by_net`` ({net: Region}) of nets other than the two."""
    import klayout.db as kdb
    out = kdb.Region()
    for n, r in by_net.items():
        if n not in (a_net, b_net):
            out += r
    return out


def _landing_free(ep, flush, a_reg, b_reg, w_top, w_under, dbu, cov_top, cov_under) -> float:
    """The share of the corner field whose lines land free: the mean of B's sidewall field's landing strip on
    A's top face (within ``w_top`` = g + T_B of B's edge, on its outer side, on A) and A's sidewall field's on
    B's underside (within g + T_A of A's edge, on B), each less the part another net's conductor covers
    (over A's face, up to B's layer: ``cov_top``; under B's, between the layers: ``cov_under``)."""
    import klayout.db as kdb
    a, b = ep.first, ep.second
    horizontal = a.dy() == 0
    ca = a.p1.y if horizontal else a.p1.x
    cb = b.p1.y if horizontal else b.p1.x
    if ca == cb:
        return 1.0
    lo = max(min(a.p1.x, a.p2.x), min(b.p1.x, b.p2.x)) if horizontal else max(min(a.p1.y, a.p2.y), min(b.p1.y, b.p2.y))
    hi = min(max(a.p1.x, a.p2.x), max(b.p1.x, b.p2.x)) if horizontal else min(max(a.p1.y, a.p2.y), max(b.p1.y, b.p2.y))
    if hi <= lo:
        return 1.0
    towards_a = 1 if ca > cb else -1
    n_b = -towards_a if flush else towards_a      # B's outer side
    n_a = towards_a if flush else -towards_a      # A's outer side

    def strip(c0, n, w):
        c1 = c0 + n * int(round(w / dbu))
        c0, c1 = min(c0, c1), max(c0, c1)
        return kdb.Region(kdb.Box(lo, c0, hi, c1) if horizontal else kdb.Box(c0, lo, c1, hi))

    def free(face, cov):
        area = face.area()
        return 1.0 if area == 0 else 1 - (face & cov).area() / area
    return (free(strip(cb, n_b, w_top) & a_reg, cov_top) + free(strip(ca, n_a, w_under) & b_reg, cov_under)) / 2


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
