"""The corner field the 2.5D terms of ``capacitance.py`` leave out between an edge and a conductor of a
higher layer beside it (offset in plan); the same-layer field round a corner is ``wedge.py``'s.

The 2.5D terms send an edge's field down (the fringe, to what lies under the strip beside it), up
only where another net's conductor lies over that strip (shared by area), and sideways only to a
same-layer edge facing it in projection (the lateral term, ``section.py``). Against FastCap2 that misses
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
VPDR's metal2 with TG's metal2 line 0.98 um beside it (TG to FD +18 -> +10 %). The strips' parts are
measured on the layers' boxes, all pairs of a layer pair at once (``_free_share``: exact where the
layers are Manhattan and their nets do not overlap, KLayout's booleans otherwise).

Charge: each of these fields was counted by the 2.5D terms as fringe of the edges bounding it (going
mostly to the substrate), so a coupling c takes half its length-equivalent from each edge's fringe:
``c / 2 / fringe(T, z)`` of its fringe length (``fringe.fringe``).
"""
from __future__ import annotations

import math
from typing import NamedTuple

from .fringe import fringe
from .plane import covered_area, rects
from .topface import eps_fringe

KAPPA = 1.6    # the two sidewall-to-face regions (2 by the construction), set on a metal1 / metal2 pair


def corner(eps: float, t_b: float, g: float, d: float) -> float:
    """Coupling per length (F/m) of an edge and an upper conductor's edge g over its top and d beside it in plan."""
    ang = 1.0 if d <= 0 else (2 / math.pi) * math.atan((g + t_b) / d)
    return KAPPA * eps * (2 / math.pi) * math.log(1 + math.pi * t_b / (2 * g)) * ang


SAMPLES = 8     # points along an edge that is not parallel to its partner, where their distance is taken


def _parallel(ep) -> bool:
    """Whether the two edges of an edge pair run parallel (their distance the same all along)."""
    a, b = ep.first, ep.second
    return (a.dx() * b.dy() - a.dy() * b.dx()) == 0


def _spread(ep) -> list:
    """The distances (dbu) from SAMPLES points spread along the pair's first edge to its second edge: two edges
    that are not parallel (a line crossing another off the axes) face each other at a distance that changes
    along them, and the corner field is a cross-section's, taken where each point is."""
    import klayout.db as kdb
    a, b = ep.first, ep.second
    out = []
    for k in range(SAMPLES):
        t = (k + 0.5) / SAMPLES
        p = kdb.Point(round(a.p1.x + (a.p2.x - a.p1.x) * t), round(a.p1.y + (a.p2.y - a.p1.y) * t))
        out.append(b.distance_abs(p))         # to the line through the second edge (the pair is its projection)
    return out


def corner_couplings(cpl, geo, stack, i, spent) -> None:
    """Add the corner field of layer ``i``'s edges to every higher layer's conductors of other nets to
    ``cpl``, and the fringe length (m) it takes from each edge to ``spent[(layer, net)]``. The edge pairs
    with one upper layer are taken together: their nets, the covered parts of their gaps and their
    landing strips as arrays over the pairs."""
    import klayout.db as kdb
    import numpy as np
    cond = stack.conductors[i]
    nets = geo.wires.get(cond.name, {})
    if not nets:
        return
    dbu = geo.dbu
    top = cond.top
    reach = int(round(cond.z / dbu))
    lower = _merged(nets)
    inner = lower.sized(-1)            # flush edges (d = 0) are then 1 dbu apart: the separation check finds them
    own = _Layer.of(nets, lower)
    blocking = [(top, lower)]          # (height, conductors) between A's top and the upper layer
    covers = []                        # the layers above A so far (``_Layer``)
    per_a = fringe(eps_fringe(stack, cond.z, cond.thickness, cond.z), cond.thickness, cond.z)
    for cb in stack.conductors[i + 1:]:
        up = geo.wires.get(cb.name, {})
        if not up:
            continue
        upper = _merged(up)
        g = cb.z - top
        block = kdb.Region()
        for zk, rk in blocking:
            grow = int(round((zk - top) / 2 / dbu))
            block += rk.sized(grow) if grow > 0 else rk
        blocking.append((cb.z, upper))
        theirs = _Layer.of(up, upper)
        covers_under = list(covers)            # the layers between A's top and B's bottom
        covers.append(theirs)                  # ... and B's: over A's top face
        apart = inner.separation_check(upper, reach, False, kdb.Region.Projection, None, None, None, True)
        over = lower.overlap_check(upper, reach, False, kdb.Region.Projection, None, None, None, True)
        pairs = [(e, False) for e in apart.each()] + [(e, True) for e in over.each()]
        if not pairs:
            continue
        ends = np.array([(e.first.x1, e.first.y1, e.first.x2, e.first.y2, e.second.x1, e.second.y1, e.second.x2,
                          e.second.y2) for e, _ in pairs], dtype=np.int64).reshape(-1, 8)
        a_nets, b_nets = _nets_at(own, ends[:, :4]), _nets_at(theirs, ends[:, 4:])
        keep = [k for k, (a, b) in enumerate(zip(a_nets, b_nets)) if a is not None and b is not None and a != b]
        if not keep:
            continue
        pairs, ends = [pairs[k] for k in keep], ends[keep]
        a_nets, b_nets = [a_nets[k] for k in keep], [b_nets[k] for k in keep]
        flush = np.array([f for _, f in pairs], dtype=bool)
        xs, ys = ends[:, 0::2], ends[:, 1::2]           # the gap: the box the two edges span
        gaps = np.stack([xs.min(axis=1), ys.min(axis=1), xs.max(axis=1), ys.max(axis=1)], axis=1)
        area = (gaps[:, 2] - gaps[:, 0]) * (gaps[:, 3] - gaps[:, 1])
        gap = ~flush & (area > 0)
        free = np.ones(len(pairs))
        free[gap] = 1 - covered_area(rects(block), gaps[gap]) / area[gap]
        free = free * _landing_free(_strips(ends, flush, g + cb.thickness, g + cond.thickness, dbu),
                                    np.array(a_nets), np.array(b_nets), own, theirs, covers, covers_under)
        per_b = fringe(eps_fringe(stack, cb.z, cb.thickness, cb.z), cb.thickness, cb.z)
        eps = stack.eps_band(cond.z, cb.top)      # the corner field: between A's and B's levels
        for (ep, fl), a_net, b_net, f in zip(pairs, a_nets, b_nets, free.tolist()):
            d = 0.0 if fl else ep.distance() * dbu
            per = corner(eps, cb.thickness, g, d) if _parallel(ep) else \
                sum(corner(eps, cb.thickness, g, x * dbu) for x in _spread(ep)) / SAMPLES
            c = per * f * (ep.first.length() + ep.second.length()) / 2 * dbu
            if c <= 0:
                continue
            cpl.add(a_net, b_net, c, ("corner", cond.name, cb.name, True))
            spent[(cond.name, a_net)] += c / 2 / per_a
            spent[(cb.name, b_net)] += c / 2 / per_b


def _merged(nets):
    """The union of the regions of ``nets`` ({net: Region}), merged."""
    import klayout.db as kdb
    out = kdb.Region()
    for r in nets.values():
        out += r
    out.merge()
    return out


class _Layer(NamedTuple):
    """A layer's conductors: its regions by net, their boxes (``_labelled``) with each box's net as a list
    and as an array, and whether the boxes are ``exact``: each net's boxes tile its shapes and no two nets
    overlap, so the boxes of any set of nets are disjoint and tile its union. Checked as: the union is
    Manhattan (KLayout's ``non_rectilinear`` finds none of its polygons: its area is exact) and the boxes'
    areas add up to its area (they add up to more where a box overshoots its net's shape or two nets
    overlap)."""
    nets: dict
    boxes: object
    names: list
    labels: object
    exact: bool

    @classmethod
    def of(cls, nets, merged):
        """The layer of ``nets`` ({net: Region}), ``merged`` their union (``_merged``)."""
        import numpy as np
        boxes, names = _labelled(nets)
        exact = (merged.non_rectilinear().is_empty()
                 and np.sum((boxes[:, 2] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 1])) == merged.area())
        return cls(nets, boxes, names, np.array(names), bool(exact))


def _nets_at(layer, edges):
    """The net whose shape carries each of ``edges`` (rows x1, y1, x2, y2): that of the first box of
    ``layer`` (``_Layer``) within 2 dbu of the edge's midpoint, None where there is none."""
    boxes = layer.boxes
    x, y = (edges[:, 0:1] + edges[:, 2:3]) / 2, (edges[:, 1:2] + edges[:, 3:4]) / 2
    hit = (boxes[:, 0] - 2 <= x) & (x <= boxes[:, 2] + 2) & (boxes[:, 1] - 2 <= y) & (y <= boxes[:, 3] + 2)
    return [layer.names[j] if h else None for j, h in zip(hit.argmax(axis=1).tolist(), hit.any(axis=1).tolist())]


def _strips(ends, flush, w_top, w_under, dbu):
    """The landing strips of the edge pairs (rows: A's edge's x1, y1, x2, y2, then B's; ``flush``: B's edge
    over A): on A's top face within ``w_top`` (m) of B's edge on its outer side, on B's underside within
    ``w_under`` of A's edge on its outer side, both over the edges' common span. Boxes (left, bottom,
    right, top; dbu) of each, and whether the pair has strips (its edges not in line, with a common span)."""
    import numpy as np
    vertical = ends[:, 1] != ends[:, 3]
    q = np.where(vertical[:, None], ends[:, [1, 0, 3, 2, 5, 4, 7, 6]], ends)     # x along the edges
    ca, cb = q[:, 1], q[:, 5]
    lo = np.maximum(np.minimum(q[:, 0], q[:, 2]), np.minimum(q[:, 4], q[:, 6]))
    hi = np.minimum(np.maximum(q[:, 0], q[:, 2]), np.maximum(q[:, 4], q[:, 6]))
    towards_a = np.where(ca > cb, 1, -1)
    n_b = np.where(flush, -towards_a, towards_a)      # B's outer side (A's is the other)

    def strip(c0, n, w):
        c1 = c0 + n * int(round(w / dbu))
        box = np.stack([lo, np.minimum(c0, c1), hi, np.maximum(c0, c1)], axis=1)
        return np.where(vertical[:, None], box[:, [1, 0, 3, 2]], box)
    return strip(cb, n_b, w_top), strip(ca, -n_b, w_under), (ca != cb) & (hi > lo)


def _landing_free(strips, a_nets, b_nets, own, theirs, cov_top, cov_under):
    """The share of each pair's corner field whose lines land free: the mean of B's sidewall field's landing
    strip on A's top face and A's sidewall field's on B's underside (``_strips``), each less the part
    another net's conductor covers (over A's face, up to B's layer: the layers ``cov_top``; under B's,
    between the layers: ``cov_under``); 1 for a pair without strips. ``own``, ``theirs``: A's and B's
    layers (``_Layer``), ``a_nets``, ``b_nets``: the pairs' nets (arrays)."""
    import numpy as np
    top, under, has = strips
    out = np.ones(len(has))
    k = np.nonzero(has)[0]
    if len(k):
        pair = a_nets[k], b_nets[k]
        out[k] = (_free_share(top[k], a_nets[k], own, cov_top, *pair)
                  + _free_share(under[k], b_nets[k], theirs, cov_under, *pair)) / 2
    return out


def _free_share(strips, owners, layer, covers, a_nets, b_nets):
    """Of each strip's part on its owner's conductors (``owners``: a net of ``layer``), the share the
    conductors of ``covers`` (layers) of nets other than the pair's (``a_nets``, ``b_nets``) leave
    uncovered; 1 where the strip holds none of the owner. On exact layers (``_Layer``) by box arithmetic:
    the owner's boxes are disjoint, and so are one layer's boxes of any set of nets, so the overlap of
    a strip with one box of each is a box and the areas of these add up; over several cover layers by
    inclusion-exclusion, area(F & (U | L)) = area(F & U) + area(F & L) - area(F & U & L). The areas are
    integers (dbu2), exact in floating point: the result is the booleans'. Otherwise KLayout's booleans."""
    import numpy as np
    n = len(strips)
    if not (layer.exact and all(c.exact for c in covers)):
        import klayout.db as kdb
        out = np.ones(n)
        for k, (box, owner, a, b) in enumerate(zip(strips.tolist(), owners, a_nets, b_nets)):
            face = kdb.Region(kdb.Box(*box)) & layer.nets[owner]
            area = face.area()
            if area:
                out[k] = 1 - (face & _others(covers, a, b)).area() / area
        return out

    def areas(pieces):
        p, of = pieces
        return np.bincount(of, weights=(p[:, 2] - p[:, 0]) * (p[:, 3] - p[:, 1]), minlength=n)
    p, of, m = _pieces(strips, np.arange(n), layer.boxes)
    keep = layer.labels[m] == owners[of]
    face = p[keep], of[keep]
    terms = []                         # (pieces, sign): the face's part under the cover layers so far
    for c in covers:
        cut = []
        for (p, of), s in [(face, 1)] + [(t, -s) for t, s in terms]:
            p, of, m = _pieces(p, of, c.boxes)
            keep = (c.labels[m] != a_nets[of]) & (c.labels[m] != b_nets[of])
            if keep.any():
                cut.append(((p[keep], of[keep]), s))
        terms += cut
    area = areas(face)
    covered = sum((s * areas(t) for t, s in terms), np.zeros(n))
    return 1 - np.divide(covered, area, out=np.zeros(n), where=area > 0)


def _pieces(boxes, of, cut):
    """The overlaps of ``boxes`` (rows left, bottom, right, top) with the boxes ``cut``: (overlap boxes,
    the ``of`` of the box each is part of, the index of its box of ``cut``)."""
    import numpy as np
    j, m = np.nonzero((boxes[:, None, 0] < cut[:, 2]) & (cut[:, 0] < boxes[:, None, 2])
                      & (boxes[:, None, 1] < cut[:, 3]) & (cut[:, 1] < boxes[:, None, 3]))
    pieces = np.concatenate([np.maximum(boxes[j, :2], cut[m, :2]), np.minimum(boxes[j, 2:], cut[m, 2:])], axis=1)
    return pieces, of[j], m


def _others(layers, a_net, b_net):
    """The conductors of ``layers`` (``_Layer``) of nets other than the two."""
    import klayout.db as kdb
    out = kdb.Region()
    for layer in layers:
        for n, r in layer.nets.items():
            if n not in (a_net, b_net):
                out += r
    return out


def _labelled(nets):
    """Every net's shapes as boxes (``plane.rects``) and the net of each box: (boxes, [net])."""
    import numpy as np
    parts = [(rects(reg), net) for net, reg in nets.items()]
    boxes = np.concatenate([b for b, _ in parts]) if parts else np.zeros((0, 4))
    return boxes, [net for b, net in parts for _ in range(len(b))]
