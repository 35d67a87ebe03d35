"""The far field between conductors of different layers: what a conductor picks up of another's potential
beyond the reach of the 2.5D terms (a line crossing another, a line beside another a few um away in plan).

The 2.5D terms of ``capacitance.py`` couple two conductors of different layers where one lies over the
other or over the band beside its edges (area, fringe landing, the edge's field up to a conductor over
its band, corner fields): within a fringe strip of each edge, about its height over the substrate. A
line at 1 V over the substrate keeps a potential around it well beyond that: in its cross-section the
line and its image in the substrate are a line dipole, whose potential falls as 1 / d^2 only past the
heights. A grounded conductor crossing it picks up a charge from that potential all along its length.
Two metal1 / metal2 lines 0.5 um wide crossing at right angles (0.6 um apart in height): FastCap2 0.309
fF between them, the 2.5D terms 0.131 fF (the overlap's plate term 0.015 fF); half of FastCap2's figure
comes from the upper line more than 2.6 um from the lower one.

**First order** (derived here; no constant). With conductor A at 1 V and everything else grounded,
a conductor B that barely disturbs A's field (narrow beside their distance) gets, on each piece of its
surface, the charge ``-c phi_A``: c is the piece's own capacitance (what it would carry at 1 V, its
field ending on the grounded surroundings), phi_A the potential A's field has there without B (Green's
reciprocity, to first order in the pieces' coupling). So ``C_AB = sum c_b phi_A(b)`` over B's pieces,
and symmetrically ``sum c_a phi_B(a)`` over A's; the two are estimates of one number (on the crossing
above: 0.303 and 0.310 fF, with phi from each line's exact 2D cross-section, against FastCap2's 0.309).

How the kit evaluates it:

- *pieces*: each net's shapes on a layer sampled on a grid of PITCH (area pieces, at the conductor's
  bottom, carrying the plate term ``eps A / z`` to the substrate) and along its edges (edge pieces, at
  its mid-height, carrying the edge's fringe ``fringe.fringe`` per length): the isolated conductor's
  charge at 1 V in the 2.5D model's own decomposition; an edge piece's charge raised near the end of its
  line (``_line_ends``: the 2.5D charges are a cross-section's, an infinite line's, and a finite line holds
  its ends with more: without it a metal1 and a metal3 line 30 um long side by side read 13 % below
  their own long-line figure per length, FastCap2 2 %, and every coupling of upper metals, whose ends reach
  further, was low: crossings metal3 / metal4 -19 %, tees to -25 %, lines side by side to -37 %);
- *phi_A*: the potential of A's pieces at 1 V as point charges with their images in the substrate
  (``(q / 4 pi eps)(1 / r - 1 / r*)``), in the permittivity of the band between the two layers, and their
  images in the stack's top interface (``_top_interface``: GF180's air over the passivation nitride, 8.82 um
  up; the images of a charge and of its substrate image, and theirs in the substrate, first order in
  ``K = (k - k_air) / (k + k_air)`` = 0.6): a field line that would rise into oxide over the top metal turns
  back down in the air, so every coupling is higher than in oxide without end. Without it the kit had the
  passivation's effect backwards: FastCap2 gives couplings to metal5 5 - 6 % higher with the real stack than
  with oxide to infinity, the kit gave them 15 - 23 % lower (its metal5 charges, whose top-face fringe runs
  into the air, fell and nothing raised the potential), and couplings to metal5 read -15 to -20 %; with the
  images the kit's change is 2 - 6 % (ten metal5 structures). On lower metals it is about twice FastCap2's
  (-7 to -12 % against -4.5 to -6.5 %: the kit's crossings of metal1 - metal4 in oxide to infinity are 6 - 9 %
  high against FastCap2's, which the missing images had hidden; cause not found);
- *what the 2.5D terms already hold* (each piece of B sums only the charge no 2.5D term gave to A): a
  piece of B within A's fringe strip (A's height over the substrate, in plan) of A (the *band*) and an edge
  piece of B whose own strip (outward from its edge, B's height wide) reaches A (the *strip*) are two
  estimates of what a 2.5D term holds (the corner and upward fringe; the edge's fringe landing on A): the
  larger of the two counts; the same for A's pieces against B;
- *shielding*: a piece of B is left out where the plan segment from it to the nearest point of A
  crosses a conductor of another net on A's layer, B's layer or a layer between (a grounded conductor
  between them takes A's field there), looked up on a raster of RASTER;
- the coupling is the mean of the two estimates, taken from the two nets' ground couplings (to first
  order the field lines that now end on B ended on the substrate before: each net's total stays).

Reach: pieces within REACH_HALOS x the stack's halo of the other net.
"""
from __future__ import annotations

import math

PITCH = 0.5e-6        # m: the sampling of the pieces
RASTER = 0.1e-6       # m: the blocking raster's pixel
REACH_HALOS = 2.0     # pieces farther than this many halos from the other net are not coupled
LOCAL = 2.0 * PITCH   # m: a piece's neighbours (diagonal ones too), whose potential is its cross-section's (_line_ends)


def _samples(region, dbu, pitch):
    """Area pieces (x, y, area) and edge pieces (x, y, length, nx, ny outward, the index of their polygon) of a
    klayout Region (m)."""
    import klayout.db as kdb
    import numpy as np
    p = pitch / dbu
    ax, ay, aw = [], [], []
    for poly in region.merged().each():
        for t in poly.decompose_trapezoids(kdb.Polygon.TD_htrapezoids):
            pts = [(q.x, q.y) for q in t.each_point()]
            y0, y1 = min(q[1] for q in pts), max(q[1] for q in pts)
            lo = sorted(x for x, y in pts if y == y0)
            hi = sorted(x for x, y in pts if y == y1)
            n = max(1, int(math.ceil((y1 - y0) / p)))
            for k in range(n):
                ya, yb = y0 + (y1 - y0) * k / n, y0 + (y1 - y0) * (k + 1) / n
                ym = (ya + yb) / 2
                f = (ym - y0) / (y1 - y0)
                xl = lo[0] + (hi[0] - lo[0]) * f
                xr = lo[-1] + (hi[-1] - lo[-1]) * f
                m = max(1, int(math.ceil((xr - xl) / p)))
                xs = xl + (np.arange(m) + 0.5) * (xr - xl) / m
                ax.append(xs)
                ay.append(np.full(m, ym))
                aw.append(np.full(m, (xr - xl) / m * (yb - ya)))
    ex, ey, el, enx, eny, eid = [], [], [], [], [], []
    for pi, poly in enumerate(region.merged().each()):
        for hole in range(-1, poly.holes()):
            pts = list(poly.each_point_hull()) if hole < 0 else list(poly.each_point_hole(hole))
            for a, b in zip(pts, pts[1:] + pts[:1]):
                dx, dy = b.x - a.x, b.y - a.y
                ln = math.hypot(dx, dy)
                if ln == 0:
                    continue
                m = max(1, int(math.ceil(ln / p)))
                t = (np.arange(m) + 0.5) / m
                ex.append(a.x + dx * t)
                ey.append(a.y + dy * t)
                el.append(np.full(m, ln / m))
                # hulls run clockwise in KLayout, holes anticlockwise: the outward normal is (dy, -dx) either way
                enx.append(np.full(m, dy / ln))
                eny.append(np.full(m, -dx / ln))
                eid.append(np.full(m, pi))
    cat = (lambda v: np.concatenate(v) * dbu if v else np.zeros(0))
    area = (cat(ax), cat(ay), (np.concatenate(aw) * dbu * dbu) if aw else np.zeros(0))
    edge = (cat(ex), cat(ey), cat(el), np.concatenate(enx) if enx else np.zeros(0),
            np.concatenate(eny) if eny else np.zeros(0), np.concatenate(eid) if eid else np.zeros(0, dtype=int))
    return area, edge


class _Pieces:
    """A layer's pieces with their nets and charges at 1 V: rows x, y, z (m), q (F, per volt), net index,
    and for edge pieces the outward normal (0 for area pieces) and their polygon (``shape``: an index over the
    layer's polygons of every net; -1 for area pieces)."""

    def __init__(self, nets, names, dbu, z, t, eps_area, fringe_len):
        import numpy as np
        rows = []
        shapes = 0
        for k, name in enumerate(names):
            reg = nets.get(name)
            if reg is None or reg.is_empty():
                continue
            (ax, ay, aw), (ex, ey, el, nx, ny, poly) = _samples(reg, dbu, PITCH)
            zero = np.zeros(len(ax))
            rows.append((ax, ay, np.full(len(ax), z), eps_area * aw, np.full(len(ax), k), zero, zero,
                         np.zeros(len(ax), dtype=bool), np.full(len(ax), -1)))
            rows.append((ex, ey, np.full(len(ex), z + t / 2), fringe_len * el, np.full(len(ex), k), nx, ny,
                         np.ones(len(ex), dtype=bool), shapes + poly))
            shapes += int(poly.max()) + 1 if len(poly) else 0
        keys = ("x", "y", "z", "q", "net", "nx", "ny", "edge", "shape")
        for c, key in enumerate(keys):
            setattr(self, key, np.concatenate([r[c] for r in rows]) if rows else np.zeros(0))
        self.net = self.net.astype(int)
        self.edge = self.edge.astype(bool)
        self.shape = self.shape.astype(int)


def _segments(region, dbu):
    """The edges of a Region as an array of rows (x1, y1, x2, y2), m."""
    import numpy as np
    out = [(e.p1.x, e.p1.y, e.p2.x, e.p2.y) for e in region.merged().edges().each()]
    return np.array(out, dtype=float).reshape(-1, 4) * dbu


def _distance(px, py, seg):
    """Plan distance of each point to the nearest of the segments ``seg`` and that nearest point: (d, qx, qy)."""
    import numpy as np
    x1, y1, x2, y2 = (seg[:, k][None, :] for k in range(4))
    dx, dy = x2 - x1, y2 - y1
    ll = dx * dx + dy * dy
    t = np.clip(((px[:, None] - x1) * dx + (py[:, None] - y1) * dy) / np.where(ll > 0, ll, 1.0), 0.0, 1.0)
    qx, qy = x1 + t * dx, y1 + t * dy
    d2 = (px[:, None] - qx) ** 2 + (py[:, None] - qy) ** 2
    j = np.argmin(d2, axis=1)
    rows = np.arange(len(px))
    return np.sqrt(d2[rows, j]), qx[rows, j], qy[rows, j]


def _inside(px, py, seg):
    """Whether each point lies inside the region whose edges are ``seg`` (even-odd crossings of a ray to +x)."""
    import numpy as np
    x1, y1, x2, y2 = (seg[:, k][None, :] for k in range(4))
    cross = (y1 > py[:, None]) != (y2 > py[:, None])
    xi = x1 + (py[:, None] - y1) * (x2 - x1) / np.where(y2 != y1, y2 - y1, 1.0)
    return (cross & (px[:, None] < xi)).sum(axis=1) % 2 == 1


def _ray_hits(px, py, nx, ny, length, seg):
    """Whether the segment from each point along its normal for ``length`` meets the region of edges ``seg``."""
    import numpy as np
    ex, ey = px + nx * length, py + ny * length
    hit = _inside(ex, ey, seg) if len(seg) else np.zeros(len(px), dtype=bool)
    if not len(seg):
        return hit
    x1, y1, x2, y2 = (seg[:, k][None, :] for k in range(4))
    ax, ay, bx, by = px[:, None], py[:, None], ex[:, None], ey[:, None]

    def orient(ux, uy, vx, vy, wx, wy):
        return (vx - ux) * (wy - uy) - (vy - uy) * (wx - ux)
    d1, d2 = orient(x1, y1, x2, y2, ax, ay), orient(x1, y1, x2, y2, bx, by)
    d3, d4 = orient(ax, ay, bx, by, x1, y1), orient(ax, ay, bx, by, x2, y2)
    return hit | (((d1 > 0) != (d2 > 0)) & ((d3 > 0) != (d4 > 0))).any(axis=1)


class _Raster:
    """Conductors on a raster of RASTER over ``bbox`` (m): ``paint`` marks a net's shapes; per pixel the
    first two nets found there and whether a third is (nets by index; -1: none)."""

    def __init__(self, bbox):
        import numpy as np
        x0, y0, x1, y1 = bbox
        self.x0, self.y0 = x0, y0
        self.nx = max(1, int(math.ceil((x1 - x0) / RASTER)))
        self.ny = max(1, int(math.ceil((y1 - y0) / RASTER)))
        self.a = np.full((self.ny, self.nx), -1, dtype=np.int32)
        self.b = np.full((self.ny, self.nx), -1, dtype=np.int32)
        self.more = np.zeros((self.ny, self.nx), dtype=bool)

    def cells(self, x, y):
        import numpy as np
        i = ((y - self.y0) * (1 / RASTER)).astype(np.int32)
        j = ((x - self.x0) * (1 / RASTER)).astype(np.int32)
        np.clip(i, 0, self.ny - 1, out=i)
        np.clip(j, 0, self.nx - 1, out=j)
        return i, j

    def _mark(self, sel, k):
        """Add net ``k`` to the pixels ``sel`` (an index into the arrays)."""
        a, b = self.a[sel], self.b[sel]
        new_a = a == -1
        rest = ~new_a & (a != k)
        new_b = rest & (b == -1)
        third = rest & ~new_b & (b != k)
        a[new_a] = k
        b[new_b] = k
        self.a[sel], self.b[sel] = a, b
        self.more[sel] |= third

    def paint(self, reg, k, dbu):
        """Mark the pixels whose centres lie in ``reg`` (a Region, dbu) with net ``k``."""
        import klayout.db as kdb
        import numpy as np
        for poly in reg.merged().each():
            for t in poly.decompose_trapezoids(kdb.Polygon.TD_htrapezoids):
                b = t.bbox()
                if t.area() == b.area():      # a box: the pixels whose centres it holds
                    i0, i1 = (int(math.ceil((v * dbu - self.y0) / RASTER - 0.5)) for v in (b.bottom, b.top))
                    j0, j1 = (int(math.ceil((v * dbu - self.x0) / RASTER - 0.5)) for v in (b.left, b.right))
                    i0, j0 = max(i0, 0), max(j0, 0)
                    i1, j1 = min(i1, self.ny), min(j1, self.nx)
                    if i1 > i0 and j1 > j0:
                        self._mark((slice(i0, i1), slice(j0, j1)), k)
                    continue
                (ax, ay, _aw), _ = _samples(kdb.Region(t), dbu, RASTER / 2)
                i, j = self.cells(ax, ay)
                cells = np.unique(i.astype(np.int64) * self.nx + j)
                self._mark((cells // self.nx, cells % self.nx), k)

    def covered(self, x, y):
        i, j = self.cells(x, y)
        return self.a[i, j] >= 0


def _same_layer_blocked(raster, px, py, qx, qy, own):
    """Whether the plan segment from each piece (px, py) to the source's nearest point (qx, qy) crosses a
    conductor of the piece's own layer (``raster``) of a net other than its own ``own``: marched out from the
    piece, 16 pixels at a time."""
    import numpy as np
    n = len(px)
    out = np.zeros(n, dtype=bool)
    if not n:
        return out
    steps = np.maximum(1, np.ceil(np.hypot(qx - px, qy - py) / RASTER)).astype(int)
    live = np.arange(n)
    for s0 in range(1, int(steps.max()) + 1, 16):
        live = live[~out[live] & (steps[live] >= s0)]
        if not len(live):
            break
        t = np.minimum(np.arange(s0, s0 + 16)[None, :] / steps[live][:, None], 1.0)
        i, j = raster.cells(px[live][:, None] + (qx - px)[live][:, None] * t,
                            py[live][:, None] + (qy - py)[live][:, None] * t)
        a, b, more = raster.a[i, j], raster.b[i, j], raster.more[i, j]
        mine = own[live][:, None]
        bad = more | ((a >= 0) & (a != mine)) | ((b >= 0) & (b != mine))
        out[live[bad.any(axis=1)]] = True
    return out


NEAR_KINDS = ("area", "top", "down", "up", "corner")
CHUNK = 256            # sensing pieces per block of the potential's sum (its memory: CHUNK x the sources near them)
TILE = 8e-6            # m: the width of the columns a block's pieces lie in
CUTOFF_REACHES = 2.0   # sources farther in plan than this many reaches from a piece are left out of its potential


def _potential(px, py, pz, sx, sy, sz, sq, si, cutoff, inner=0.0, top=None, direct=True):
    """The potential (x 4 pi eps) at each point (px, py, pz) of the point charges sq at (sx, sy, sz), each with its
    image in the plane si under it (none where the point is not above that plane), from the sources within
    ``cutoff`` in plan: a source's image pair falls off as 1 / r^3 past the heights, so beyond twice the reach
    (16 um for GF180's 8 um halo) the sum moves by under 1 % on the test structures, and a chip's long nets do
    not make an (all pieces x all pieces) matrix; sources within ``inner`` in plan are left out too. In blocks
    of at most CHUNK points of one column TILE wide, taken along y, each against the sources within ``cutoff``
    of its box (found in the sources sorted along x). ``top`` ((height, K), ``_top_interface``): the images in
    the stack's top interface too; ``direct=False``: those alone."""
    import numpy as np
    out = np.zeros(len(px))
    if not len(px) or not len(sx):
        return out
    by_x = np.argsort(sx, kind="stable")
    sx, sy, sz, sq, si = sx[by_x], sy[by_x], sz[by_x], sq[by_x], si[by_x]
    ix = np.floor((px - px.min()) / TILE).astype(np.int64)
    order = np.lexsort((py, ix))
    col = ix[order]
    edges = np.flatnonzero(np.r_[True, col[1:] != col[:-1], True])
    for t0, t1 in zip(edges[:-1], edges[1:]):
        for i in range(t0, t1, CHUNK):
            blk = order[i:min(i + CHUNK, t1)]
            bx, by, bz = px[blk], py[blk], pz[blk]
            lo = np.searchsorted(sx, bx.min() - cutoff, side="left")
            hi = np.searchsorted(sx, bx.max() + cutoff, side="right")
            near = lo + np.flatnonzero((sy[lo:hi] >= by.min() - cutoff) & (sy[lo:hi] <= by.max() + cutoff))
            if not len(near):
                continue
            rxy = (bx[:, None] - sx[near][None, :]) ** 2 + (by[:, None] - sy[near][None, :]) ** 2
            zs, zi = sz[near][None, :], si[near][None, :]
            zp = bz[:, None]
            g = 0.0
            with np.errstate(divide="ignore"):          # a piece against itself (left out by ``inner``)
                if direct:
                    g = np.where((zp > zi) & (rxy <= cutoff * cutoff) & (rxy > inner * inner),
                                 1 / np.sqrt(rxy + (zp - zs) ** 2) - 1 / np.sqrt(rxy + (zp + zs - 2 * zi) ** 2), 0.0)
                if top is not None:     # the images in the top dielectric interface (first order in its K)
                    h, k = top
                    g = g + k * np.where((zp > zi) & (rxy <= cutoff * cutoff),
                                         1 / np.sqrt(rxy + (2 * h - zs - zp) ** 2)
                                         - 1 / np.sqrt(rxy + (2 * h - 2 * zi + zs - zp) ** 2)
                                         - 1 / np.sqrt(rxy + (zp - 2 * zi + 2 * h - zs) ** 2)
                                         + 1 / np.sqrt(rxy + (zp - 4 * zi + 2 * h + zs) ** 2), 0.0)
            out[blk] = g @ sq[near]
    return out


def _line_ends(pc, eps, cutoff) -> None:
    """Raise the charge of each edge piece of a layer's pieces ``pc`` by what its own net's potential on the layer
    lacks there against the best-held edge piece of its polygon (the middle of its longest edge): the 2.5D edge
    fringe is a cross-section's per length, as if every edge went on for ever; a line of finite length holds its
    ends at 1 V with more charge (its own charge beyond the end is missing: the potential there half an infinite
    line's), over a length of about its height. One step of the 3D self-consistency: piece i at 1 V takes
    ``1 - V_i`` from its local charge (what its neighbours within LOCAL give: the cross-section's own, scaling with
    it) and V_i from the net's pieces on the layer beyond LOCAL; with V_ref the best-held edge piece's of its
    polygon, its charge becomes ``q (1 - V_i) / (1 - V_ref)`` (never lowered; none where V_ref >= 1, a wide plate
    over a near plane whose sampled potential is no perturbation). Edge pieces only: an area piece's plate term
    is local by construction; by polygon, so a small pad of a net is not taken for the end of its long line. A
    30 um metal1 line beside a metal3 one (3 um apart in plan): the first-order coupling per length was 13 %
    below the 2D cross-section's at 30 um, 3.5 % at 120 um, where FastCap2 is 2 % below it at 30 um."""
    import numpy as np
    scale = np.ones(len(pc.x))
    v = np.zeros(len(pc.x))
    for k in np.unique(pc.net[pc.edge]):
        i = np.flatnonzero(pc.net == k)
        e = i[pc.edge[i]]
        v[e] = _potential(pc.x[e], pc.y[e], pc.z[e], pc.x[i], pc.y[i], pc.z[i], pc.q[i], pc.image[i], cutoff,
                          LOCAL) / (4 * math.pi * eps)
    for sh in np.unique(pc.shape[pc.edge]):
        e = np.flatnonzero(pc.shape == sh)
        ref = v[e].max()
        if ref < 1.0:
            scale[e] = np.maximum(1.0, (1 - v[e]) / (1 - ref))
    pc.q = pc.q * scale


COARSE = 2e-6         # m: the cells the sources are summed in for their images in the top interface (_coarse)


def _coarse(x, y, z, q, image):
    """The sources summed in cells COARSE wide in plan (per height and image plane), each at its charge's centroid:
    for their images in the top interface, at least twice the interface's height over the top metal's middle
    away (4.2 um on GF180), where a cell's spread moves their potential by (COARSE / distance)^2 / 12, ~2 %
    of a term that is itself 5 - 10 % of a coupling; a quarter of the sum's cost at 0.5 um pieces."""
    import numpy as np
    if not len(x):
        return x, y, z, q, image
    key = np.stack([np.floor(x / COARSE), np.floor(y / COARSE), z, image], axis=1)
    _u, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.ravel()
    n = int(inv.max()) + 1
    qs = np.bincount(inv, q, n)
    w = np.where(qs > 0, qs, 1.0)
    return (np.bincount(inv, q * x, n) / w, np.bincount(inv, q * y, n) / w, np.bincount(inv, z, n) / np.bincount(inv, None, n),
            qs, np.bincount(inv, image, n) / np.bincount(inv, None, n))


def _top_interface(stack, eps):
    """(height, K) of the interface between the dielectrics over the conductors and what lies over the stack (its
    last layer, reaching up without end: the air over the passivation), K = (k - k_top) / (k + k_top) the image
    coefficient of a charge in a medium of permittivity ``eps`` (k relative); None in a uniform stack."""
    from ...tech.stack import EPS0
    if len(stack.dielectrics) < 2:
        return None
    k, kt = eps / EPS0, stack.dielectrics[-1].k
    return (stack.dielectrics[-2].top, (k - kt) / (k + kt))


def far_couplings(geo, stack, cpl, fo=None) -> list:
    """[(net a, net b, C)] the far field adds between the conductors of every two layers of ``geo``, over the
    2.5D terms of ``cpl`` (a ``Couplings``: its ``near`` record between them, and every net's couplings, by
    which the far field is screened). ``fo``: ``first_order(geo, stack)`` when already computed (it does not
    depend on ``cpl``: ``capacitance.capacitances`` computes it beside the 2.5D terms)."""
    if fo is None:
        fo = first_order(geo, stack)
    return _combined(fo, cpl)


def first_order(geo, stack) -> dict:
    """The first-order far-field sums {(lower layer, upper layer, lower net, upper net, view, zone): F} of
    ``geo``: each layer's pieces in every other layer's field (``far_couplings`` weighs them against the 2.5D
    terms)."""
    import numpy as np
    from scipy.ndimage import distance_transform_edt
    from .fringe import fringe
    from .nets import FLOATING, GROUND
    from .topface import eps_fringe
    dbu = geo.dbu
    conds = [c for c in stack.conductors if geo.wires.get(c.name) and not c.device_below]
    if len(conds) < 2:
        return {}
    names = sorted({n for c in stack.conductors for n in geo.wires.get(c.name, {})})
    index = {n: k for k, n in enumerate(names)}
    boxes = [r.bbox() for c in stack.conductors for r in geo.wires.get(c.name, {}).values()]
    pad = 2 * RASTER
    bbox = (min(b.left for b in boxes) * dbu - pad, min(b.bottom for b in boxes) * dbu - pad,
            max(b.right for b in boxes) * dbu + pad, max(b.top for b in boxes) * dbu + pad)
    rasters, pieces = {}, {}
    for c in stack.conductors:
        if geo.wires.get(c.name):
            rasters[c.name] = _Raster(bbox)
            for n, r in geo.wires[c.name].items():
                rasters[c.name].paint(r, index[n], dbu)
    for c in conds:
        nets = geo.wires[c.name]
        # ground (the shield, unjoined rails) and floating fill end no coupling here: they shield (the rasters)
        pc = _Pieces({n: r for n, r in nets.items() if n != GROUND and not n.startswith(FLOATING)}, names, dbu,
                     c.z, c.thickness, stack.eps_gap(0.0, c.z) / c.z,
                     fringe(eps_fringe(stack, c.z, c.thickness, c.z), c.thickness, c.z))
        # each piece's field images in the top of the nearest conductor under it (the substrate where none is)
        pc.image = np.zeros(len(pc.x))
        for low in reversed([x for x in stack.conductors if x.top <= c.z and x.name in rasters]):
            hit = (pc.image == 0) & rasters[low.name].covered(pc.x, pc.y)
            pc.image[hit] = low.top
        _line_ends(pc, stack.eps_band(c.z, c.top), CUTOFF_REACHES * REACH_HALOS * stack.halo)
        pieces[c.name] = pc
    reach = REACH_HALOS * stack.halo
    fo = {}                     # (lower layer, upper layer, lower net, upper net, view, zone) -> F
    for i, ca in enumerate(conds):
        for cb in conds[i + 1:]:
            eps = stack.eps_band(ca.z, cb.top)
            for view, sense, src in (("B", cb, ca), ("A", ca, cb)):     # the upper layer's pieces in the lower's field, and back
                ps, pa = pieces[sense.name], pieces[src.name]
                if not len(ps.x) or not len(pa.x):
                    continue
                # the conductors between (the sensing layer's own aside), the nearer painted last: each piece sees
                # the source only where the source's net is the nearest of them in plan (a disc free of the others)
                between = [c for c in stack.conductors if min(ca.z, cb.z) <= c.z <= max(ca.z, cb.z)
                           and c.name in rasters and c is not sense]
                if src is cb:
                    between = between[::-1]
                label = np.full(rasters[src.name].a.shape, -1, dtype=np.int32)
                for c in between:
                    r = rasters[c.name]
                    label = np.where(r.a >= 0, r.a, label)
                    label = np.where(r.b >= 0, r.b, label)
                empty = label < 0
                if empty.all():
                    continue
                dist, (ii, jj) = distance_transform_edt(empty, sampling=RASTER, return_indices=True)
                pi, pj = rasters[src.name].cells(ps.x, ps.y)
                nearest = label[ii[pi, pj], jj[pi, pj]]
                d = dist[pi, pj]
                src_nets = np.unique(pa.net)
                k = np.flatnonzero(np.isin(nearest, src_nets) & (nearest != ps.net) & (d > 0) & (d <= reach))
                if not len(k):
                    continue
                qx = rasters[src.name].x0 + (jj[pi[k], pj[k]] + 0.5) * RASTER
                qy = rasters[src.name].y0 + (ii[pi[k], pj[k]] + 0.5) * RASTER
                keep = ~_same_layer_blocked(rasters[sense.name], ps.x[k], ps.y[k], qx, qy, ps.net[k])
                k = k[keep]
                for ka in np.unique(nearest[k]):
                    kk = k[nearest[k] == ka]
                    a_net = names[ka]
                    e = ps.edge[kk]
                    strip = np.zeros(len(kk), dtype=bool)
                    if e.any():              # an edge piece whose own fringe strip reaches A (the 2.5D terms' fringe)
                        seg_a = _segments(geo.wires[src.name][a_net], dbu)
                        hits = _ray_hits(ps.x[kk[e]], ps.y[kk[e]], ps.nx[kk[e]], ps.ny[kk[e]], sense.z, seg_a)
                        strip[np.flatnonzero(e)[hits]] = True
                    m = pa.net == ka
                    phi = _potential(ps.x[kk], ps.y[kk], ps.z[kk], pa.x[m], pa.y[m], pa.z[m], pa.q[m], pa.image[m],
                                     CUTOFF_REACHES * reach)
                    top = _top_interface(stack, eps)
                    if top is not None:
                        phi += _potential(ps.x[kk], ps.y[kk], ps.z[kk], *_coarse(pa.x[m], pa.y[m], pa.z[m], pa.q[m],
                                                                                 pa.image[m]),
                                          CUTOFF_REACHES * reach, top=top, direct=False)
                    c = ps.q[kk] * phi / (4 * math.pi * eps)
                    band = (d[kk] <= src.z) & ~strip
                    for kb in np.unique(ps.net[kk]):
                        b_net = names[kb]
                        lower, upper = (a_net, b_net) if view == "B" else (b_net, a_net)
                        own = ps.net[kk] == kb
                        for zone, sel in (("strip", own & strip), ("band", own & band), ("far", own & ~band & ~strip)):
                            if sel.any():
                                key = (ca.name, cb.name, lower, upper, view, zone)
                                fo[key] = fo.get(key, 0.0) + float(c[sel].sum())
    return fo


def _combined(fo, cpl) -> list:
    """``far_couplings``' pairs from the first-order sums ``fo`` and the 2.5D terms ``cpl``."""
    total = {}
    for (x, y), v in cpl.c.items():
        total[x] = total.get(x, 0.0) + v
        total[y] = total.get(y, 0.0) + v

    def free(n, m):
        """The share of net n's charge (at 1 V, the 2.5D terms) that ends on ground or on m, not on a third net."""
        t = total.get(n, 0.0)
        return (cpl.to_ground(n) + cpl.pair(n, m)) / t if t > 0 else 1.0
    out = {}
    for key in {k[:4] for k in fo}:
        _la, _lb, a, b = key
        n = cpl.near.get(key, {})
        v = {x: n.get(x, 0.0) for x in NEAR_KINDS}
        screen = free(a, b) * free(b, a)
        f = {(vw, z): screen * fo.get((*key, vw, z), 0.0) for vw in "AB" for z in ("strip", "band", "far")}
        c_b = (v["area"] + v["top"] + max(v["down"], f[("B", "strip")]) + max(v["up"] + v["corner"], f[("B", "band")])
               + f[("B", "far")])
        c_a = (v["area"] + v["top"] + max(v["up"], f[("A", "strip")]) + max(v["down"] + v["corner"], f[("A", "band")])
               + f[("A", "far")])
        extra = (c_a + c_b) / 2 - sum(v.values())
        if extra > 0:
            pair = (a, b) if a < b else (b, a)
            out[pair] = out.get(pair, 0.0) + extra
    return [(a, b, c) for (a, b), c in sorted(out.items())]
