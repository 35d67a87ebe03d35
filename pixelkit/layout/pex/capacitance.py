"""Wiring capacitance of every net, to ground and to every other net, from the geometry and the stack.

A 2.5D model (the decomposition field solvers are checked against; ``fastcap.py`` is that
check). For each conductor layer (poly off the gates, metal1 - metal5), bottom to top, and
each net on it:

- **area**: the part of the net's shape over a conductor of another net below (the nearest
  one; what it covers shields what lies deeper) couples to it as a parallel plate
  ``eps A / h`` (h: the gap between the two); the rest sees the substrate ``eps A / z``.
  Diffusions and wells are conductors at the substrate surface (their junction capacitance is
  the device models', not counted here).
- **fringe**: each edge of the shape adds ``eps 1.40 (T / h)^0.222`` per length to what lies
  under the band just outside it (width h), each part of the band by the flux an edge over a plane
  at that part's gap sends to it at its distance from the edge (below): the single-line fringe of T. Sakurai and K. Tamaru,
  "Simple formulas for two- and three-dimensional capacitances", IEEE Trans. Electron Devices
  30(2), 1983 (their isolated-line formula less its plate term). A neighbour of another net on
  the same layer keeps of that edge's fringe what the cross-section's 2D solve says it keeps
  (``section.kept``: the pair's ground against the line alone; no constant; it replaced the law
  ``S / (S + 0.7 h)`` whose 0.7 was set with FastCap2 on a metal1 pair). That fringe is an
  isolated edge's, its top face's field wrapping round the edge: where a conductor of another net
  lies over the top face within h of the edge (a MIM capacitor's top plate over its bottom plate, a
  line crossing over another) it takes the top face's share from under it (``topface.py``, derived
  there from the field of a half-plane over a ground plane: no constant), coupled to that conductor.
  How the fringe spreads over the band: as an edge over a plane puts its charge on the plane
  (``fringe.landing``: the half-plane's field, flux ``(eps/pi) ln(u(x1)/u(x0))`` into the plane's
  strip x0 .. x1 beyond the edge, ``1 + u + ln u = pi x / h``). The band is cut into STRIPS strips by
  distance from the edge (each twice as wide as the one inside it) and each part under a strip weighs that flux for its own gap times its
  length along the edge (area over strip width): a conductor near the edge at a small gap takes most
  of the fringe, one far out in the band (beyond its own fringe strip, ~ its gap wide) little. Weighed
  by a / h alone (before), a part 1 um beside a metal2 edge and 0.6 um under it took four times the
  substrate's share per area: a metal1 block with a metal2 line 1 um beside it, FastCap2 151 aF, the
  kit 187 so, 132 now; TG's metal2 line to FD +31 / +21 % -> +10 / +12 %. Over one gap (lines over
  the substrate alone) the total is unchanged; only its spread moves.
- **lateral**: facing edges of two nets on the same layer, S apart over a projected length l
  (nearest only: a shape between them shields), couple by the coupling per length of their
  cross-section, solved in 2D (``section.py``: the two lines, w1 and w2 wide, over the nearest
  conductor under the space between them and under the nearest one over it, by boundary elements;
  no constant) times l. It replaced the formula of J.-H. Chern et al. (IEEE Electron Device Letters
  13(1), 1992), +12.6 / +29.4 % against FastCap2 at S / H = 1.6 / 2.6 (docs/post-layout.md).
- **corner fields** (``cornerfield.py``, its derivation there): an edge and a conductor of another net
  on a higher layer beside it in plan (B's sidewall to A's top face and A's sidewall to B's underside,
  by quarter-circle field lines; one constant, set with FastCap2 on a metal1 / metal2 line pair; a
  third net's conductor over the strip where those lines land takes them), and (``wedge.py``)
  sidewalls of one layer that see each other round a corner with no facing projection (perpendicular
  faces: the quarter plane between them opened to a half plane by ``w = z^2``, half circles there;
  flush faces end to end: half circles; no constant). Each takes half its charge from the fringe of
  each of its two edges.
- **far field** (``farfield.py``, its derivation there): between conductors of two layers beyond
  the reach of the terms above (a line crossing another: most of their coupling lies along the lines
  away from the overlap; lines side by side a few um apart in plan), to first order by Green's
  reciprocity over the conductors' sampled charge, taken from the two nets' ground. No constant.

Every coupling is between two named nets; ``0`` is ground (substrate, and the shield).
"""
from __future__ import annotations

from collections import defaultdict

from . import section
from . import farfield
from .beside import beside
from .cornerfield import corner_couplings
from .farfield import far_couplings
from .fringe import fringe, landing, wide, width_of
from .nets import GROUND
from .plane import Plane
from .stacks import Stacking, screened
from .topface import covered_top, eps_fringe
from .wedge import wedge_couplings

class Couplings:
    """Symmetric net-pair capacitances (F); ``(a, a)`` is never stored. ``near``: the 2.5D terms between
    conductors of two layers by kind ({(lower layer, upper layer, lower net, upper net): {kind: F}}: area,
    top, down, up, corner), which the far field (``farfield.py``) weighs its own estimate against."""

    def __init__(self):
        self.c = defaultdict(float)
        self.near = defaultdict(lambda: defaultdict(float))

    def add(self, a: str, b: str, value: float, near: tuple | None = None) -> None:
        """Add ``value`` between nets a and b; ``near`` = (kind, a's layer, b's layer, whether a is the lower
        one) records it as a 2.5D term between two layers."""
        if a == b or value <= 0:
            return
        self.c[(a, b) if a < b else (b, a)] += value
        if near and GROUND not in (a, b) and "surface" not in near[1:3]:
            kind, la, lb, a_lower = near
            key = (la, lb, a, b) if a_lower else (lb, la, b, a)
            self.near[key][kind] += value

    def total(self, net: str) -> float:
        return sum(v for k, v in self.c.items() if net in k)

    def to_ground(self, net: str) -> float:
        return self.c.get((GROUND, net) if GROUND < net else (net, GROUND), 0.0)

    def pair(self, a: str, b: str) -> float:
        return self.c.get((a, b) if a < b else (b, a), 0.0)

    def items(self):
        return sorted(self.c.items())


def _below(geo, stack, i):
    """Conductors under layer ``i``, nearest first: [Plane] at their tops, the surface (diffusions, wells) last."""
    out = [Plane(c.top, geo.wires[c.name], c.name) for c in reversed(stack.conductors[:i]) if geo.wires.get(c.name)]
    return out + ([Plane(0.0, geo.surface, "surface")] if geo.surface else [])


def _above(geo, stack, i):
    """Conductors over layer ``i``, nearest first: [Plane] at their bottoms."""
    return [Plane(c.z, geo.wires[c.name], c.name) for c in stack.conductors[i + 1:] if geo.wires.get(c.name)]


def _under(region, below, z, device=False):
    """(net, area dbu2, gap h, its layer) of each part of ``region`` (at height z) over the nearest conductor
    below it; what is over nothing sees the substrate (net 0, h = z). ``device``: the conductor right
    below is a capacitor's bottom plate (the part over it is the device's, counted nowhere)."""
    for m, part, h, layer in _under_parts(region, below, z, device):
        yield m, part.area(), h, layer


def _under_parts(region, below, z, device=False):
    """(net, Region, gap h, its layer) of each part of ``region``, as ``_under``."""
    rest = region
    for k, plane in enumerate(below):
        union = plane.near(rest)
        hit = rest & union
        if hit.is_empty():
            continue
        if device and k == 0:
            rest = rest - union
            continue
        for m, reg in plane.nets_near(hit):
            part = hit & reg
            if not part.is_empty():
                yield m, part, z - plane.z, plane.name
        rest = rest - union
    if not rest.is_empty():
        yield GROUND, rest, z, "substrate"


def _down(cpl, net, pieces, eps, t, per_area, weight, strips=None, areas=None, layer="", widen=None):
    """The downward fringe of a part of a band (``per_area``: edge length per band area; ``eps(h)`` its
    permittivity down to a plane h below; ``widen``: its factor where it lands on the substrate, ``_widen``)
    to what lies under
    it, ``pieces`` (``_under_parts`` of that part). ``strips`` ([(Region, x0, x1)]: the band by distance from
    the edge, ``_strips``) with ``areas`` ({(piece, strip): area}, ``_areas_by_strip``): each piece's share
    is the flux an edge over a plane at the piece's gap sends to the piece's distance (``fringe.landing``)
    times its length along the edge; without, its area over its gap (a / h, as the plate term: the
    field goes to the nearer conductor; shared by area alone, C11's metal5 strap 6.1 um up gave most of
    its edge field to the substrate rather than to the bottom plate 0.9 um under it: +57 % against
    FastCap2, +14 % by a / h)."""
    if areas is None:
        parts = [(m, a, h, a / h, lay) for m, part, h, lay in pieces for a in (part.area(),)]
    else:
        parts = [(m, a, h, a / (x1 - x0) * landing(h, x0, x1), lay)
                 for i, (m, _part, h, lay) in enumerate(pieces)
                 for k, (_strip, x0, x1) in enumerate(strips) for a in (areas.get((i, k), 0),) if a]
    total = sum(p[1] for p in parts)
    conductance = sum(p[3] for p in parts)
    for m, a, h, w, lay in parts:
        f = fringe(eps(h), t, h) * (widen if widen and lay == "substrate" else 1.0)
        cpl.add(net, m, f * per_area * total * w / conductance * weight(h), ("down", layer, lay, False))


def _areas_by_strip(groups, strips) -> list:
    """[{(piece index, strip index): area (dbu2)}] of each group's pieces (``_under_parts``) in each strip:
    every piece of every group in one region labelled by its index, one boolean per strip (a strip's
    edges are the costly operand: a boolean per piece and strip took ~5 x the CPU)."""
    import klayout.db as kdb
    lab, where = kdb.Region(), []
    for g, pieces in enumerate(groups):
        for i, (_m, part, _h, _lay) in enumerate(pieces):
            for p in part.each():
                lab.insert(kdb.PolygonWithProperties(p, {0: len(where)}))
            where.append((g, i))
    out = [defaultdict(int) for _ in groups]
    for k, (strip, _x0, _x1) in enumerate(strips):
        for p in lab.and_(strip, kdb.Region.NoPropertyConstraint).each():
            g, i = where[p.properties()[0]]
            out[g][(i, k)] += p.area()
    return out


def _fringe_band(cpl, net, band, below, above, stack, t, z, edge_len, band_area, device=False, strips=None, layer="",
                 widen=None):
    """Share the fringe of ``edge_len`` (m) of a shape by what lies under and over ``band`` (the strip
    beside its edges, by area). Where a conductor of another net lies over the strip (gap h_u), the
    sidewall's field splits between the two planes: the downward fringe keeps h_u / (h_u + h_d)
    and the upward one, ``fringe(t, h_u)``, h_d / (h_u + h_d). The permittivity of each: the stack's
    along the fringe's path (``topface.eps_fringe`` down to a plane h below; ``Stack.eps_gap`` up to one above)."""
    if band_area <= 0 or edge_len <= 0:
        return

    def eps(h):
        return eps_fringe(stack, z, t, h)

    def eps_up(hu):
        return stack.eps_gap(z + t, z + t + hu)
    per_area = edge_len / band_area
    rest = band
    top_z = z + t
    jobs = []                  # (part of the band, weight of its downward fringe by h_d)
    for plane in above:
        union = plane.near(rest)
        hit = rest & union
        if hit.is_empty():
            continue
        hu = plane.z - top_z
        for m, reg in plane.nets_near(hit):
            part = hit & reg
            a = part.area()
            if not a:
                continue
            h_d = z   # the substrate (the nearest plane below decides each part's h_d in _down)
            cpl.add(net, m, fringe(eps_up(hu), t, hu) * per_area * a * h_d / (hu + h_d), ("up", layer, plane.name, True))
            jobs.append((part, lambda hd, hu=hu: hu / (hu + hd)))
        rest = rest - union
    jobs.append((rest, lambda hd: 1.0))
    pieces = [list(_under_parts(part, below, z, device)) for part, _w in jobs]
    weighed = [k for k, ps in enumerate(pieces) if strips and len(ps) > 1]   # one piece takes it all
    areas = dict(zip(weighed, _areas_by_strip([pieces[k] for k in weighed], strips) if weighed else ()))
    for k, (_part, weight) in enumerate(jobs):
        _down(cpl, net, pieces[k], eps, t, per_area, weight, strips, areas.get(k), layer, widen)


def capacitances(geo, stack) -> Couplings:
    """Every wiring capacitance of ``geo`` (a ``nets.NetGeometry``) with ``stack``'s numbers."""
    cpl = Couplings()
    spent = defaultdict(float)          # (layer, net) -> fringe length (m) the corner field took
    polygons = sum(r.count() for nets in geo.wires.values() for r in nets.values())
    first_order = beside(farfield.first_order, polygons, geo, stack)     # the far field, meanwhile
    try:
        _near_terms(cpl, geo, stack, spent, Stacking(geo, stack))
    except BaseException:
        first_order.cancel()
        raise
    for a, b, c in far_couplings(geo, stack, cpl, first_order()):
        cpl.add(a, b, c)
        for n in (a, b):                  # to first order each net's total stays: taken from its ground
            key = (GROUND, n) if GROUND < n else (n, GROUND)
            cpl.c[key] = max(0.0, cpl.c.get(key, 0.0) - c)
    float_out(cpl)
    return cpl


def _near_terms(cpl, geo, stack, spent, stacking) -> None:
    """The 2.5D terms of every conductor layer (``capacitances``), bottom to top, into ``cpl``."""
    dbu = geo.dbu
    halo = int(round(stack.halo / dbu))
    for i, cond in enumerate(stack.conductors):
        nets = geo.wires.get(cond.name, {})
        if not nets:
            continue
        z, t = cond.z, cond.thickness
        below = _below(geo, stack, i)
        above = _above(geo, stack, i)
        # area, to the nearest conductor below or the substrate
        for net, reg in nets.items():
            for m, a, h, lay in _under(reg, below, z, cond.device_below):
                cpl.add(net, m, stack.eps_gap(z - h, z) * a * dbu * dbu / h, ("area", cond.name, lay, False))
        eps = stack.eps_band(z, z + t)     # the lateral field: along the layer's band
        # lateral: facing edges of different nets, nearest only (a shielded space check of the layer)
        polys, labels = [], []
        for k, (_net, reg) in enumerate(sorted(nets.items())):
            for p in reg.each():
                polys.append(p)
                labels.append(k + 1)
        shielded = defaultdict(float)    # (net, edge key) -> length in dbu lost to a neighbour, weighted
        if len(nets) > 1:
            pairs = _facing(polys, labels, halo)
            owners = _nets_of(nets, [e for ep in pairs for e in (ep.first, ep.second)], dbu)
            gaps = _plane_gaps([ep.polygon(0) for ep in pairs], below, above, z, t)
            section.prepare([(wa, wb, t, ep.distance() * dbu, h_d, h_u)
                             for ep, (a_net, wa), (b_net, wb), (h_d, h_u) in zip(pairs, owners[0::2], owners[1::2], gaps)
                             if a_net is not None and b_net is not None and a_net != b_net and ep.distance() > 0])
            runs = _stacked_pairs(stacking, i, pairs, owners)
            for ep, (a_net, wa), (b_net, wb), (h_d, h_u), (down, up, da, db) in zip(pairs, owners[0::2], owners[1::2], gaps, runs):
                if a_net is None or b_net is None or a_net == b_net:
                    continue
                s = ep.distance() * dbu
                la, lb = ep.first.length() * dbu, ep.second.length() * dbu
                if s <= 0 or min(la, lb) <= 0:
                    continue
                cpl.add(a_net, b_net, eps * section.pair(wa, wb, t, s, h_d, h_u)[0] * (la + lb) / 2
                        * screened(stack, i, da, db, s, down, up))
                keep_a, keep_b = section.kept(wa, wb, t, s, h_d, h_u)
                shielded[a_net] += (1 - keep_a) * la
                shielded[b_net] += (1 - keep_b) * lb
        corner_couplings(cpl, geo, stack, i, spent)
        wedge_couplings(cpl, geo, stack, i, spent, stacking)
        # fringe downwards, less what neighbours, the corner field and covers over its top face take (a
        # capacitor's top plate has none: its bottom plate, which encloses it, takes its sidewalls' field)
        made = {}

        def covers(above=above, below=below, made=made):
            if "cover" not in made:
                made["cover"] = _covers(above, below)
            return made["cover"]
        for net, reg in (nets.items() if not cond.device_below else ()):
            h = z
            wb = max(1, int(round(h / dbu)))
            band = reg.sized(wb) - reg
            perim = reg.perimeter() * dbu
            taken = 0.0
            for m, lay, lost in covered_top(net, reg, above, z, t, dbu):
                cpl.add(net, m, fringe(eps_fringe(stack, z, t, h), t, h) * lost, ("top", cond.name, lay, True))
                taken += lost
            length = max(0.0, perim - shielded.get(net, 0.0) - spent[(cond.name, net)] - taken)
            strips = _strips(reg, wb, dbu) if STRIPS else None
            _fringe_band(cpl, net, band, below, above, stack, t, z, length, band.area(), cond.device_below, strips,
                         cond.name, _widen(reg, covers, t, z, dbu))


def _covers(above, below):
    """The conductors over and under a layer (the surface's diffusions aside), merged: what ``_widen`` takes off a
    polygon's top face (built once per layer, on first use)."""
    import klayout.db as kdb
    cover = kdb.Region()
    for plane in list(above) + [pl for pl in below if pl.name != "surface"]:
        cover += plane.union
    return cover


def _widen(reg, cover, t, z, dbu) -> float:
    """The fringe of ``reg``'s edges to the substrate (z below) over ``fringe.fringe``'s (``fringe.wide``), each
    polygon at its own width (``fringe.width_of``) or, where that is narrower, the width of its part that
    faces the substrate alone: no conductor above it (the wide conductor's extra fringe is its top face's
    charge) nor below it (over a nearer conductor its field ends there); weighed by its perimeter, never
    below 1 (a narrow line keeps Sakurai and Tamaru's edge, on which the kit's narrow lines were checked with
    FastCap2: 4 - 10 % above the solve at 0.23 um). ``cover``: ``_covers``' Region, or a function giving it."""
    import klayout.db as kdb
    num = den = 0.0
    for p in reg.each():
        perim = p.perimeter() * dbu
        den += perim
        k = wide(width_of(p.area() * dbu * dbu, perim), t, z)
        if k > 1.0:                       # only a wide polygon asks what covers it (wide grows with the width)
            if not isinstance(cover, kdb.Region):
                cover = cover()
            free = kdb.Region(p) - cover.interacting(kdb.Region(p))
            k = max(1.0, wide(width_of(free.area() * dbu * dbu, free.perimeter() * dbu), t, z)) \
                if not free.is_empty() else 1.0
        num += perim * max(1.0, k)
    return num / den if den > 0 else 1.0


def float_out(cpl: Couplings) -> None:
    """Eliminate the floating conductors (nets ``~...``: dummy fill) from ``cpl``: a floating node f with
    couplings C_if is at the potential sum C_if V_i / C_f (its charge zero), which leaves each pair of its
    neighbours i, j coupled by C_if C_jf / C_f more (the node eliminated from the capacitance matrix, a
    Schur complement); one floating node after the other."""
    from .nets import FLOATING
    floating = sorted({n for k in cpl.c for n in k if n.startswith(FLOATING)})
    for f in floating:
        nb = {}
        for (a, b), v in list(cpl.c.items()):
            if f in (a, b):
                nb[b if a == f else a] = v
                del cpl.c[(a, b)]
        total = sum(nb.values())
        items = sorted(nb.items())
        for i, (a, va) in enumerate(items):
            for b, vb in items[i + 1:]:
                cpl.add(a, b, va * vb / total)


STRIPS = 5    # strips of the fringe band, each twice as wide as the one inside it


def _strips(reg, width, dbu):
    """The band of ``width`` (dbu) beside ``reg``'s edges in STRIPS strips by distance from them, each
    twice as wide as the one inside it (the landing flux changes on the scale of a part's gap: fine near
    the edge, where the small gaps are): [(strip, x0 m, x1 m)]."""
    out, inner, a0 = [], reg, 0
    for k in range(STRIPS):
        a1 = max(a0 + 1, width * (2 ** (k + 1) - 1) // (2 ** STRIPS - 1))
        outer = reg.sized(a1)
        out.append((outer - inner, a0 * dbu, a1 * dbu))
        inner, a0 = outer, a1
    return out


def _facing(polys, labels, halo: int) -> list:
    """The facing edge pairs of different nets (``labels``) less than ``halo`` (dbu) apart, unshielded, each
    once: ``facing.facing_pairs`` on a Manhattan layer, else KLayout's shielded space check (the same pairs,
    slower at the stack's halo; it reports a pair from each side)."""
    import klayout.db as kdb
    from .facing import facing_pairs, manhattan
    if manhattan(polys):
        return facing_pairs(polys, labels, halo)
    layer = kdb.Region()
    for p, n in zip(polys, labels):
        layer.insert(kdb.PolygonWithProperties(p, {0: n}))
    pairs = layer.space_check(halo, False, kdb.Region.Projection, None, None, None, True,
                              kdb.Region.NoOppositeFilter, kdb.Region.NoRectFilter, False,
                              kdb.Region.DifferentPropertiesConstraint)
    seen, out = set(), []
    for ep in pairs.each():
        canon = tuple(sorted((_canon(ep.first), _canon(ep.second))))
        if canon not in seen:
            seen.add(canon)
            out.append(ep)
    return out


def _stacked_pairs(stacking, i, pairs, owners) -> list:
    """[(down, up, depth a, depth b)] of each facing pair: how many routing layers both nets' faces continue on,
    flush, under and over conductor ``i`` (``stacks.Stacking.runs``: the layers both run on, contiguous), and
    how deep (m) each face's conductor reaches back from it (``stacks.Stacking.depth``, at most 2 um)."""
    import numpy as np
    if not pairs:
        return []
    e = [(ep.first, ep.second) for ep in pairs]
    ma = np.array([((a.p1.x + a.p2.x) / 2, (a.p1.y + a.p2.y) / 2) for a, _b in e], dtype=float)
    mb = np.array([((b.p1.x + b.p2.x) / 2, (b.p1.y + b.p2.y) / 2) for _a, b in e], dtype=float)

    def normal(edges, towards, mids):
        d = np.array([(x.p2.x - x.p1.x, x.p2.y - x.p1.y) for x in edges], dtype=float)
        n = np.stack([-d[:, 1], d[:, 0]], axis=1) / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-30)[:, None]
        return n * np.where(((towards - mids) * n).sum(axis=1) >= 0, 1.0, -1.0)[:, None]
    gap = np.array([ep.distance() for ep in pairs], dtype=float) / 2
    na, nb = [o[0] for o in owners[0::2]], [o[0] for o in owners[1::2]]
    nrm_a, nrm_b = normal([a for a, _ in e], mb, ma), normal([b for _, b in e], ma, mb)
    da, ua = stacking.runs(i, na, ma, nrm_a, gap)
    db, ub = stacking.runs(i, nb, mb, nrm_b, gap)
    cap = 2e-6 / stacking.geo.dbu        # the pair's widths' cap (``_nets_of``)
    wa, wb = np.array([o[1] for o in owners[0::2]]), np.array([o[1] for o in owners[1::2]])
    deep_a = np.minimum(stacking.depth(i, na, ma, nrm_a), cap) * stacking.geo.dbu
    deep_b = np.minimum(stacking.depth(i, nb, mb, nrm_b), cap) * stacking.geo.dbu
    deep_a, deep_b = np.where(deep_a > 0, deep_a, wa), np.where(deep_b > 0, deep_b, wb)   # none found: the width
    return list(zip(np.minimum(da, db).tolist(), np.minimum(ua, ub).tolist(), deep_a.tolist(), deep_b.tolist()))


def _canon(e):
    """An edge without its direction."""
    a, b = (e.p1.x, e.p1.y), (e.p2.x, e.p2.y)
    return (a, b) if a <= b else (b, a)


def _plane_gaps(polys, below, above, z, t) -> list:
    """The planes of each pair's cross-section (``polys``: the space between its edges): [(gap down to the
    nearest conductor under that space, the substrate when there is none; gap up to the nearest one over
    it, None when there is none)]."""
    import numpy as np
    h = np.full(len(polys), z)
    open_ = np.ones(len(polys), dtype=bool)
    for plane in below:
        hit = open_ & plane.covers(polys)
        h[hit] = z - plane.z
        open_ &= ~hit
    up = np.full(len(polys), np.nan)
    open_[:] = True
    for plane in above:
        hit = open_ & plane.covers(polys)
        up[hit] = plane.z - (z + t)
        open_ &= ~hit
    return [(d, None if u != u else u) for d, u in zip(h.tolist(), up.tolist())]


def _nets_of(nets, edges, dbu) -> list:
    """[(net, width m)] of the shape carrying each of ``edges`` (the one touching a 2 x 2 dbu probe at the
    edge's midpoint; nets in ``nets``' order, (None, 0) when none does); the width is 2 area / perimeter
    of that shape (a line's width), at most 2 um."""
    import klayout.db as kdb
    import numpy as np
    shapes = [(net, p) for net, reg in nets.items() for p in reg.each()]
    bb = np.array([(b.left, b.bottom, b.right, b.top) for _n, p in shapes for b in (p.bbox(),)]).reshape(-1, 4)
    mids = [e.p1 + (e.p2 - e.p1) * 0.5 for e in edges]
    c = np.array([(m.x, m.y) for m in mids]).reshape(-1, 2)
    near = ((bb[None, :, 0] <= c[:, None, 0] + 1) & (bb[None, :, 2] >= c[:, None, 0] - 1)
            & (bb[None, :, 1] <= c[:, None, 1] + 1) & (bb[None, :, 3] >= c[:, None, 1] - 1))
    out = []
    for m, cand in zip(mids, near):
        probe = kdb.Box(m.x - 1, m.y - 1, m.x + 1, m.y + 1)
        hit = next((shapes[k] for k in np.flatnonzero(cand) if shapes[k][1].touches(probe)), None)
        out.append((None, 0.0) if hit is None else
                   (hit[0], min(2.0 * hit[1].area() / hit[1].perimeter(), 2000.0) * dbu))
    return out
