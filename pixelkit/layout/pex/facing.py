"""Facing edges of different nets on one layer: the pairs the lateral coupling is computed on.

What KLayout's shielded space check (``Region.space_check`` with projection metrics, shielding and
different-properties constraint, the nets as properties) reports, computed directly for a Manhattan
layer: two edges of polygons of different nets, anti-parallel, each on the outer side of the other,
less than ``halo`` apart, over the part where their projections overlap (``first``: that part of one
edge, ``second``: of the other, each in its edge's direction). A pair is dropped (shielded) when one
other edge crosses the gap between them across the whole overlap (KLayout's rule: an edge that cuts
both connecting sides of the pair's quadrilateral; a partial cover leaves the pair whole). KLayout
checks each polygon against the polygons of the other nets, so from one side the shields are that
side's own polygon and the other nets' polygons, not its net's other polygons; a pair either side
keeps is reported.

KLayout finds candidates and shields with a box scanner at the check distance: at the stack's 8 um
halo nearly every edge of a cell meets every other, and its shielding pass went over every pair of
them (DUALPIX_COL's metal3: 864 edges, 1.9 s of CPU). Here the candidates are one comparison of every
horizontal (vertical) edge with every other and the shielding one test of each candidate against
the layer's edges, vectorised (0.03 s). ``tests/test_extraction.py`` checks the pairs against
KLayout's on random layers and on the drawn dual pixel; a layer with an edge off the axes is left
to KLayout's check (``capacitance._facing``).
"""
from __future__ import annotations

import numpy as np


_BLOCK = 4_000_000    # cells of the candidate x edge tables per block (bounds the memory on a large cell)


def manhattan(polys) -> bool:
    """Whether every edge of ``polys`` (klayout.db polygons) is horizontal or vertical."""
    return all(e.dx() == 0 or e.dy() == 0 for p in polys for e in p.each_edge())


def _edges(polys, nets):
    """Rows (x1, y1, x2, y2, net, polygon) of every edge of ``polys`` (hulls and holes), ``nets[i]`` the
    net of polygon i."""
    rows = [(e.p1.x, e.p1.y, e.p2.x, e.p2.y, n, k) for k, (p, n) in enumerate(zip(polys, nets)) for e in p.each_edge()]
    return np.array(rows, dtype=np.int64).reshape(-1, 6)


def _pairs_along(e, halo):
    """The facing pairs among edges ``e`` that run along x (rows x1, y1, x2, y2, net, polygon: y1 == y2):
    (index of the lower edge, index of the upper one, overlap start, overlap end) of those no edge shields.
    KLayout's hulls run clockwise: an edge running towards +x has its polygon below it."""
    if len(e) == 0:
        return np.zeros((0, 4), dtype=np.int64)
    lo, hi = np.minimum(e[:, 0], e[:, 2]), np.maximum(e[:, 0], e[:, 2])
    y, net, poly, up = e[:, 1], e[:, 4], e[:, 5], e[:, 2] > e[:, 0]       # up: the outer side is +y
    a, b = np.nonzero(up)[0], np.nonzero(~up)[0]          # a: facing up (the lower edge), b: facing down
    s = y[b][None, :] - y[a][:, None]
    x0 = np.maximum(lo[a][:, None], lo[b][None, :])
    x1 = np.minimum(hi[a][:, None], hi[b][None, :])
    ok = (s > 0) & (s < halo) & (x1 > x0) & (net[a][:, None] != net[b][None, :])
    i, j = np.nonzero(ok)
    cand = np.stack([a[i], b[j], x0[i, j], x1[i, j]], axis=1)
    # shielded: another edge along x with y in [y_lower, y_upper] covering [x0, x1]; from each side the
    # shields are its own polygon and the other nets' polygons, the pair kept if either side keeps it
    kept = np.zeros(len(cand), dtype=bool)
    idx = np.arange(len(e))[None, :]
    step = max(1, _BLOCK // len(e))          # candidates per block: a block's tables hold ~_BLOCK cells
    for k in range(0, len(cand), step):
        c = cand[k:k + step]
        cover = ((y[None, :] >= y[c[:, 0:1]]) & (y[None, :] <= y[c[:, 1:2]])
                 & (lo[None, :] <= c[:, 2:3]) & (hi[None, :] >= c[:, 3:4])
                 & (idx != c[:, 0:1]) & (idx != c[:, 1:2]))
        for side in (c[:, 0:1], c[:, 1:2]):
            shields = (poly[None, :] == poly[side]) | (net[None, :] != net[side])
            kept[k:k + step] |= ~(cover & shields).any(axis=1)
    return cand[kept]


def facing_pairs(polys, nets, halo: int):
    """[klayout.db.EdgePair] of the facing edges of different nets of the Manhattan polygons ``polys``
    (``nets[i]``: polygon i's net, an int) less than ``halo`` (dbu) apart that no edge shields, each
    pair once."""
    import klayout.db as kdb
    e = _edges(polys, nets)
    out = []
    horizontal = e[:, 1] == e[:, 3]
    for along_x, sel in ((True, horizontal & (e[:, 0] != e[:, 2])), (False, ~horizontal)):
        sub = e[sel] if along_x else e[sel][:, [1, 0, 3, 2, 4, 5]] * np.array([1, -1, 1, -1, 1, 1])
        # a vertical edge is an edge along x after (x, y) -> (y, -x), which keeps the hulls clockwise
        for i, j, x0, x1 in _pairs_along(sub, halo).tolist():
            pts = []
            for k in (i, j):
                x1k, yk, x2k = (int(v) for v in sub[k, :3])
                ends = (x0, x1) if x2k > x1k else (x1, x0)
                pts.append([(v, yk) if along_x else (-yk, v) for v in ends])
            (p, q), (r, t) = pts
            out.append(kdb.EdgePair(kdb.Edge(kdb.Point(*p), kdb.Point(*q)), kdb.Edge(kdb.Point(*r), kdb.Point(*t))))
    return out
