"""The conductors of one layer by net, with a box index for the region booleans of ``capacitance.py``.

A KLayout boolean (``a & b``) walks every edge of both operands; the fringe bands, their strips and
the top faces are small, a layer's union is not (DUALPIX_COL's metal1: 104 polygons, ~0.2 ms per
boolean against ~0.01 ms for the few polygons near a band). ``near`` hands the boolean only the
union's polygons whose boxes overlap the operand's box, ``nets_near`` only the nets whose boxes do:
a polygon whose box misses the operand's box shares no area with it, so every area is the one the
whole layer gives. ``covers`` answers for many boxes at once whether the layer shares area with each
(the lateral term's gap to the nearest plane), from the union's non-overlapping boxes on a Manhattan
layer; ``rects`` and ``covered_area`` are that box arithmetic, shared with the corner field and the
wedges. The capacitance tables of the kit's cells are the ones computed without the index to ~1e-15
(the order of the sums).
"""
from __future__ import annotations


class Plane:
    """Conductors at one height: ``z`` (the gap's reference: their top seen from above, their bottom
    seen from below), ``nets`` ({net: Region}), ``union`` (their merged Region) and the layer's ``name``."""

    def __init__(self, z: float, nets: dict, name: str = ""):
        import klayout.db as kdb
        self.z, self.nets, self.name = z, nets, name
        u = kdb.Region()
        for r in nets.values():
            u += r
        self.union = u.merged()
        self._polys = list(self.union.each())
        self._boxes = [_ltrb(p.bbox()) for p in self._polys]
        self._names = list(nets)
        self._net_boxes = [_ltrb(nets[n].bbox()) for n in self._names]
        self._rects = None          # the union as non-overlapping boxes (False: not Manhattan), when asked

    def near(self, region):
        """The union's polygons whose boxes overlap ``region``'s (a Region: ``region & near`` is
        ``region & union``)."""
        import klayout.db as kdb
        idx = _overlapping(self._boxes, region)
        return self.union if len(idx) == len(self._polys) else kdb.Region([self._polys[k] for k in idx])

    def covers(self, polys):
        """Whether the union shares area with each of ``polys`` (klayout.db polygons): a bool array. Boxes
        against the union's non-overlapping boxes (exact on a Manhattan layer), the rest by a boolean."""
        import klayout.db as kdb
        import numpy as np
        if self._rects is None:
            self._rects = rects(self.union) if self.union.non_rectilinear().is_empty() else False
        out = np.zeros(len(polys), dtype=bool)
        boxed = np.array([p.is_box() for p in polys], dtype=bool) & (self._rects is not False)
        if boxed.any():
            b, r = _boxes([p.bbox() for p, k in zip(polys, boxed) if k])[:, None, :], self._rects[None, :, :]
            out[boxed] = ((r[..., 0] < b[..., 2]) & (r[..., 2] > b[..., 0])
                          & (r[..., 1] < b[..., 3]) & (r[..., 3] > b[..., 1])).any(axis=1)
        for k in np.flatnonzero(~boxed):
            g = kdb.Region(polys[k])
            out[k] = not (self.near(g) & g).is_empty()
        return out

    def nets_near(self, region):
        """[(net, Region)] of the nets whose boxes overlap ``region``'s, in ``nets``' order."""
        return [(self._names[k], self.nets[self._names[k]]) for k in _overlapping(self._net_boxes, region)]


def _boxes(boxes):
    """klayout.db boxes as an array of rows (left, bottom, right, top)."""
    import numpy as np
    return np.array([_ltrb(b) for b in boxes], dtype=np.int64).reshape(-1, 4)


def rects(region):
    """The merged ``region`` as non-overlapping boxes (its trapezoids' boxes: exact on a Manhattan layer),
    an array of (left, bottom, right, top)."""
    import klayout.db as kdb
    import numpy as np
    boxes = [_ltrb(t.bbox()) for p in region.merged().each() for t in p.decompose_trapezoids(kdb.Polygon.TD_htrapezoids)]
    return np.array(boxes, dtype=float).reshape(-1, 4)


def covered_area(rects, boxes):
    """Area (dbu2) of each of ``boxes`` (rows left, bottom, right, top) that ``rects`` (non-overlapping boxes, as ``rects()``
    gives them) cover."""
    import numpy as np
    w = np.clip(np.minimum(rects[:, 2], boxes[:, 2:3]) - np.maximum(rects[:, 0], boxes[:, 0:1]), 0, None)
    h = np.clip(np.minimum(rects[:, 3], boxes[:, 3:4]) - np.maximum(rects[:, 1], boxes[:, 1:2]), 0, None)
    return np.sum(w * h, axis=1)


def _ltrb(b) -> tuple:
    """A klayout.db box as (left, bottom, right, top)."""
    return b.left, b.bottom, b.right, b.top


def _overlapping(boxes, region) -> list:
    """Indices of ``boxes`` ([(left, bottom, right, top)]) that overlap ``region``'s box (sharing area, not
    only an edge); a loop, not numpy: on a layer's tens of boxes numpy's call overhead is ~3 x the loop."""
    if region.is_empty():
        return []
    x0, y0, x1, y1 = _ltrb(region.bbox())
    return [k for k, (l, b, r, t) in enumerate(boxes) if l < x1 and r > x0 and b < y1 and t > y0]
