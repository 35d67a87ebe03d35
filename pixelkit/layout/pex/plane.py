"""The conductors of one layer by net, with a box index for the region booleans of ``capacitance.py``.

A KLayout boolean (``a & b``) walks every edge of both operands; the fringe bands, their strips and
the top faces are small, a layer's union is not (DUALPIX_COL's metal1: 104 polygons, ~0.2 ms per
boolean against ~0.01 ms for the few polygons near a band). ``near`` hands the boolean only the
union's polygons whose boxes overlap the operand's box, ``nets_near`` only the nets whose boxes do:
a polygon whose box misses the operand's box shares no area with it, so every area is the one the
whole layer gives (``tests/test_extraction.py`` compares the tables with and without the index).
"""
from __future__ import annotations


class Plane:
    """Conductors at one height: ``z`` (the gap's reference: their top seen from above, their bottom
    seen from below), ``nets`` ({net: Region}) and ``union`` (their merged Region)."""

    def __init__(self, z: float, nets: dict):
        import klayout.db as kdb
        import numpy as np
        self.z, self.nets = z, nets
        u = kdb.Region()
        for r in nets.values():
            u += r
        self.union = u.merged()
        self._polys = list(self.union.each())
        self._boxes = _boxes([p.bbox() for p in self._polys])
        self._names = list(nets)
        self._net_boxes = _boxes([nets[n].bbox() for n in self._names])

    def near(self, region):
        """The union's polygons whose boxes overlap ``region``'s (a Region: ``region & near`` is
        ``region & union``)."""
        import klayout.db as kdb
        idx = _overlapping(self._boxes, region)
        return self.union if len(idx) == len(self._polys) else kdb.Region([self._polys[k] for k in idx])

    def nets_near(self, region):
        """[(net, Region)] of the nets whose boxes overlap ``region``'s, in ``nets``' order."""
        return [(self._names[k], self.nets[self._names[k]]) for k in _overlapping(self._net_boxes, region)]


def _boxes(boxes):
    import numpy as np
    return np.array([(b.left, b.bottom, b.right, b.top) for b in boxes], dtype=np.int64).reshape(-1, 4)


def _overlapping(boxes, region):
    """Indices of ``boxes`` that overlap ``region``'s box (sharing area, not only an edge)."""
    import numpy as np
    if region.is_empty():
        return []
    b = region.bbox()
    hit = (boxes[:, 0] < b.right) & (boxes[:, 2] > b.left) & (boxes[:, 1] < b.top) & (boxes[:, 3] > b.bottom)
    return np.flatnonzero(hit).tolist()
