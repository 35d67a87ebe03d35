"""Conductors stacked on their own net: a pad stack's sections screen each other.

Two pad stacks side by side (metal1 - metalN of one net over each other, joined by vias, beside another
net's) couple as two tall conductors, not as N independent line pairs: each metal's section has its own
net's metal over and under it, which takes the field its top and bottom faces would send across the gap
(FastCap2 on GF180's layered stack: pad stacks without their vias within 0.1 % of those with them, so the
via levels' faces are screened as if solid). Summing each metal's isolated 2D section overstates the
stacks' grouped 2D coupling by 18 - 44 % (1 - 1.5 um pads 0.8 - 3 um apart, metal1 - metal2 .. metal5),
and the flush faces' half circles (``wedge.py``) taken over each metal's thickness alone leave out the
via levels' height of the faces, which the stacks' ends see as one face.

So, where the facing edges of both nets have their own net's metal flush over them (and under them) on
the next conductor layer (a probe just inside each edge covered by the same net there, one just outside
not: the faces are flush):

- **lateral** (``capacitance.py``): the layer's pair section times ``share / alone``, both solved with each
  conductor as deep as it reaches back from its face (its box's extent along the face's normal, at most
  2 um as the pair's widths; a square pad is its side deep, where the pair's width, 2 area / perimeter,
  is half that): ``share`` the layer's part of the grouped 2D coupling (every stacked layer's pair of rectangles in one solve, ``section._maxwell``:
  the charge on this layer's rectangle of one net with the whole other stack at 1 V, averaged over the two
  directions), ``alone`` the same layer's pair solved by itself in the same frame. No constant.
- **flush faces end to end** (``wedge.py``'s half circles): the faces' height is the layer's thickness plus
  half the gap to the stacked layer above and half the gap to the one below (each gap is shared by the two
  layers it separates). Faces round a corner (``wedge.right_wedges``) are left at the layer's thickness: no
  FastCap2 structure checks them, and on the kit's column cell they raised one coupling by 9 %
  (DUALPIX_COL col_p - out_p 1.50 -> 1.63 fF).

Checked: FastCap2 on the structure sets' pad stacks (``tests/test_extraction_structures.py``; eight stacks
metal1 - metal2 .. metal5, 1 - 1.5 um pads, 0.8 - 3 um apart): 3 -> 6 of 8 within 10 %.
"""
from __future__ import annotations

IN, OUT = 10e-9, 200e-9      # probes inside / outside a face (m): flush within OUT


def layers(stack) -> list:
    """Indices of the conductors a stack can run through (a capacitor's top plate is no routing layer)."""
    return [k for k, c in enumerate(stack.conductors) if not c.device_below]


class Stacking:
    """Which of a layer's faces continue on their own net's metal flush over / under them."""

    def __init__(self, geo, stack):
        self.geo, self.stack, self.order = geo, stack, layers(stack)
        self._boxes = {}

    def _net_boxes(self, k, net):
        key = (k, net)
        if key not in self._boxes:
            from .plane import rects
            reg = self.geo.wires.get(self.stack.conductors[k].name, {}).get(net)
            import numpy as np
            self._boxes[key] = rects(reg) if reg is not None else np.zeros((0, 4))
        return self._boxes[key]

    def _covered(self, k, net, pts):
        import numpy as np
        b = self._net_boxes(k, net)
        if not len(b):
            return np.zeros(len(pts), dtype=bool)
        x, y = pts[:, 0:1], pts[:, 1:2]
        return ((b[:, 0] < x) & (x < b[:, 2]) & (b[:, 1] < y) & (y < b[:, 3])).any(axis=1)

    def flush(self, k, nets, mids, normals, out=None):
        """For faces of ``nets`` (one a face) on conductor ``k`` with midpoints ``mids`` (n, 2 dbu) and
        outward unit ``normals`` (n, 2): whether each net's metal on conductor ``k`` covers a probe IN inside
        the face and not one ``out`` (dbu, per face; default OUT) outside it: a bool array."""
        import numpy as np
        dbu = self.geo.dbu
        o = (np.full(len(mids), OUT / dbu) if out is None else np.minimum(out, OUT / dbu))[:, None]
        inside, outside = mids - normals * (IN / dbu), mids + normals * o
        res = np.zeros(len(mids), dtype=bool)
        for net in set(nets):
            sel = np.array([n == net for n in nets], dtype=bool)
            res[sel] = self._covered(k, net, inside[sel]) & ~self._covered(k, net, outside[sel])
        return res

    def depth(self, k, nets, mids, normals):
        """Each face's conductor's extent (dbu) along the face's normal: the box (``plane.rects``) of its net on
        conductor ``k`` holding a probe IN inside the face (0 where none does)."""
        import numpy as np
        inside = mids - normals * (IN / self.geo.dbu)
        res = np.zeros(len(mids))
        for net in set(nets):
            sel = np.flatnonzero(np.array([n == net for n in nets], dtype=bool))
            b = self._net_boxes(k, net)
            if not len(b):
                continue
            x, y = inside[sel, 0:1], inside[sel, 1:2]
            hit = (b[:, 0] < x) & (x < b[:, 2]) & (b[:, 1] < y) & (y < b[:, 3])
            ext = np.where(np.abs(normals[sel, 0:1]) > np.abs(normals[sel, 1:2]), b[:, 2] - b[:, 0], b[:, 3] - b[:, 1])
            res[sel] = np.where(hit, ext, 0).max(axis=1)
        return res

    def runs(self, i, nets, mids, normals, out=None):
        """(down, up): for each face on conductor ``i``, how many routing layers under / over it its net
        continues on, flush and contiguous (arrays of ints)."""
        import numpy as np
        down, up = np.zeros(len(mids), dtype=int), np.zeros(len(mids), dtype=int)
        if i not in self.order:              # a capacitor's plate: no stack
            return down, up
        pos = self.order.index(i)
        for direction, count in ((-1, down), (1, up)):
            live = np.ones(len(mids), dtype=bool)
            p = pos + direction
            while live.any() and 0 <= p < len(self.order):
                hit = self.flush(self.order[p], nets, mids, normals, out) & live
                count[hit] += 1
                live &= hit
                p += direction
        return down, up

    def extension(self, i, down, up):
        """The height (m) a face on conductor ``i`` gains from its net's stacked layers: half the gap to the
        next stacked layer under it (``down`` > 0) and over it (``up`` > 0); arrays."""
        import numpy as np
        if i not in self.order:
            return np.zeros(len(np.atleast_1d(down)))
        pos, c = self.order.index(i), self.stack.conductors
        cond = c[i]
        below = (cond.z - c[self.order[pos - 1]].top) / 2 if pos > 0 else 0.0
        above = (c[self.order[pos + 1]].z - cond.top) / 2 if pos + 1 < len(self.order) else 0.0
        return np.where(np.asarray(down) > 0, below, 0.0) + np.where(np.asarray(up) > 0, above, 0.0)


_SHARES: dict = {}


def screened(stack, i, wa, wb, s, down, up) -> float:
    """``share / alone`` of the lateral pair on conductor ``i`` (widths wa, wb, s apart, m) whose two stacks
    run ``down`` / ``up`` routing layers under / over it: the layer's part of the grouped 2D coupling over its
    pair solved alone (both over the substrate, units of the permittivity); 1 when nothing is stacked."""
    if not down and not up:
        return 1.0
    from . import section
    key = (i, section._nm(wa), section._nm(wb), section._nm(s), int(down), int(up))
    if key not in _SHARES:
        import numpy as np
        order = layers(stack)
        pos = order.index(i)
        group = order[pos - down:pos + up + 1]
        rects = []
        for k in group:
            c = stack.conductors[k]
            rects += [(-wa, c.z, 0.0, c.top), (s, c.z, s + wb, c.top)]
        c = stack.conductors[i]
        m = section._maxwell([rects], [0])[0]
        alone = section.pair(wa, wb, c.thickness, s, c.z)[0]
        a = list(range(0, 2 * len(group), 2))
        b = [x + 1 for x in a]
        me = group.index(i)
        share = -(m[b[me], a].sum() + m[a[me], b].sum()) / 2
        _SHARES[key] = float(min(1.0, max(0.0, share / alone))) if alone > 0 else 1.0
    return _SHARES[key]
