"""The independent check of the extraction: FastCap2 (a 3D boundary-element capacitance solver,
pip ``fastcap2``) on the same geometry.

Every net's shapes become closed conductors: each merged polygon of a layer extruded from the
stack's z to z + thickness (faces split into rectangles, meshed), diffusions and wells as sheets
in the substrate's plane (z = 0), the substrate a ground sheet around them reaching beyond the
window by the stack's height, the shield (net ``0``) on that ground. The dielectric: the stack's one k,
or its layers (``[[stack.dielectrics]]``): each interface between two layers of different k a plane of
dielectric panels over the substrate sheet's extent (holes where a conductor crosses it), every
conductor panel with the permittivity of the layer it lies in (walls split at the interfaces).
Vias are left out (their area is < 1 % of the wires'; the 2.5D model leaves them out too) unless asked
(``vias=True``, the via-stack structure): then each via of ``geo.vias`` is a prism joining its two metals. FastCap2 returns the Maxwell matrix;
its off-diagonal terms are the couplings, a row's sum the net's capacitance to ground.

``compare`` runs the kit's 2.5D model and FastCap2 on one window of the cell, so both see
the same shapes (cut at the window's edge).
"""
from __future__ import annotations

from dataclasses import replace

from .nets import GROUND, NetGeometry

EDGE = 0.05  # um: the rim of every face meshed finer (charge crowds at edges)
GAP = 20   # dbu between a diffusion / well island and the substrate sheet around it
SURF = "#s"      # a net's diffusions / wells: a conductor of their own (their ground capacitance is the junction's)


def clip(geo: NetGeometry, window) -> NetGeometry:
    """The part of ``geo`` inside ``window`` (x0, y0, x1, y1 in m)."""
    import klayout.db as kdb
    d = geo.dbu
    box = kdb.Region(kdb.Box(*(int(round(v / d)) for v in window)))
    wires = {}
    for layer, nets in geo.wires.items():
        for net, reg in nets.items():
            r = reg & box
            if not r.is_empty():
                wires.setdefault(layer, {})[net] = r
    surface = {n: r & box for n, r in geo.surface.items() if not (r & box).is_empty()}
    vias = {zz: {n: r & box for n, r in nets.items() if not (r & box).is_empty()} for zz, nets in geo.vias.items()}
    return replace(geo, wires=wires, surface=surface, bbox=tuple(window), vias=vias)


def _quad(surf, p0, p1, p2, md):
    """A meshed rectangle p0, p1, p2 (corner, its two neighbours), the rim finer when it is large."""
    import math
    a, b = math.dist(p0, p1), math.dist(p0, p2)
    if min(a, b) > 4 * EDGE:
        surf.add_meshed_quad(p0, p1, p2, max_dim=md, edge_width=EDGE)
    else:
        surf.add_meshed_quad(p0, p1, p2, max_dim=md)


def _prism(surf, reg, d, z0, z1, md, cuts=()):
    """The closed surface of ``reg`` extruded from z0 to z1: top and bottom faces as rectangles, the
    walls along the merged outlines only (no face inside the conductor). ``surf(z)``: the surface a
    panel at height z goes to (its dielectric); ``cuts``: heights where the walls are split."""
    import klayout.db as kdb
    zs = [z0] + sorted(c for c in cuts if z0 < c < z1) + [z1]
    for p in reg.merged().each():
        for t in p.decompose_trapezoids(kdb.Polygon.TD_htrapezoids):
            for z, outward in ((z0, -1e-9), (z1, 1e-9)):     # the medium beside each face
                _face(surf(z + outward), t, d, z, md)
        for e in p.each_edge():
            for za, zb in zip(zs, zs[1:]):
                _quad(surf((za + zb) / 2), (e.p1.x * d, e.p1.y * d, za), (e.p2.x * d, e.p2.y * d, za),
                      (e.p1.x * d, e.p1.y * d, zb), md)


def _sheet(surf, reg, d, z, md):
    """``reg`` as a conductor sheet of no thickness at height z (the substrate surface)."""
    import klayout.db as kdb
    for p in reg.merged().each():
        for t in p.decompose_trapezoids(kdb.Polygon.TD_htrapezoids):
            _face(surf, t, d, z, md)


def _face(surf, trap, d, z, md):
    """A horizontal face at height z: ``trap`` (a trapezoid with horizontal top and bottom, dbu) as a
    meshed rectangle, or, where its sides slant (a layout off the axes), as a meshed parallelogram and the
    triangle left over, the triangle split into four until its sides are within ``md``."""
    b = trap.bbox()
    if trap.area() == b.area():
        _quad(surf, (b.left * d, b.bottom * d, z), (b.right * d, b.bottom * d, z), (b.left * d, b.top * d, z), md)
        return
    pts = [(q.x, q.y) for q in trap.each_point()]
    y0, y1 = b.bottom, b.top
    lo = sorted(x for x, y in pts if y == y0)
    hi = sorted(x for x, y in pts if y == y1)
    (b0, b1), (t0, t1) = (lo[0], lo[-1]), (hi[0], hi[-1])
    w = min(b1 - b0, t1 - t0)
    if w > 0:
        surf.add_meshed_quad((b0 * d, y0 * d, z), (t0 * d, y1 * d, z), ((b0 + w) * d, y0 * d, z), max_dim=md)
    if b1 - b0 > t1 - t0:
        tri = ((b0 + w, y0), (b1, y0), (t1, y1))
    else:
        tri = ((t0 + w, y1), (t1, y1), (b1, y0))
    if tri[0] != tri[1]:
        _triangle(surf, [(x * d, y * d, z) for x, y in tri], md)


def _triangle(surf, tri, md):
    """A triangle (three 3D points) split into four by its sides' middles until every side is within ``md``."""
    import math
    a, b, c = tri
    if max(math.dist(a, b), math.dist(b, c), math.dist(c, a)) <= md:
        # the native triangle: fastcap2 2.1's Surface.add_tri hands its three points to the quad call
        super(type(surf), surf)._add_tri(a, b, c)
        return
    ab, bc, ca = (tuple((u + v) / 2 for u, v in zip(p, q)) for p, q in ((a, b), (b, c), (c, a)))
    for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)):
        _triangle(surf, t, md)


#: a dielectric layer thinner than this (um) is solved merged with the layer below it, by their series
#: permittivity: two interfaces closer than a few panels give FastCap2 no converged answer (a 0.05 um
#: layer between two plates: +2.1 / +2.4 / +3.4 % at 0.5 / 0.25 / 0.1 um panels against +2.2 % exact)
THIN = 0.2


def solver_layers(stack, scale: float = 1.0) -> list:
    """[(z0, z1, k)] of the stack's dielectrics as FastCap2 solves them (``scale``: units per m), each layer
    thinner than THIN um merged with the one below it by their series permittivity (GF180's 0.05 um nitride
    liner over the 0.32 um STI: 0 - 0.37 um at k 4.25, the same vertical field)."""
    out = []
    for a, b, k in stack._layers():
        a, b = a * scale, b * scale
        if out and (b - a) * 1e6 / scale < THIN:
            a0, _b0, k0 = out.pop()
            k = (b - a0) / ((a - a0) / k0 + (b - a) / k)
            a = a0
        out.append((a, b, k))
    return out


def solve(geo: NetGeometry, stack, mesh: float = 0.4e-6, sub_margin: float | None = None, vias: bool = False) -> dict:
    """{(a, b): coupling F, (a, a): total F} of every net of ``geo`` by FastCap2 (lengths in um inside);
    ``vias``: with the vias of ``geo.vias`` as conductors joining their metals."""
    import fastcap2 as fc
    import klayout.db as kdb
    um = 1e6
    d = geo.dbu * um
    x0, y0, x1, y1 = (v * um for v in geo.bbox)
    margin = (stack.conductors[-1].top * um) if sub_margin is None else sub_margin * um
    md = mesh * um
    layers = solver_layers(stack, um)
    layered = len(layers) > 1
    surfaces = {}

    def k_at(z):
        return next(k for a, b, k in layers if a <= z < b or b == float("inf"))

    def surf(net):
        def at(z):
            k = k_at(z) if layered else 1.0
            key = (net, k)
            if key not in surfaces:
                surfaces[key] = fc.Surface(name=net.replace(".", "_").replace("#", "_") or "x")
            return surfaces[key]
        return at
    sub = kdb.Region(kdb.Box(*(int(round(v / d)) for v in (x0 - margin, y0 - margin, x1 + margin, y1 + margin))))
    islands = kdb.Region()
    for reg in geo.surface.values():
        islands += reg
    cuts = [b for a, b, k in layers[:-1]]
    _sheet(surf(GROUND)(1e-9), sub - islands.sized(GAP), d, 0.0, max(md, 1.0))
    solids = []                                   # (z0, z1, Region): what the interface planes go round
    for cond in stack.conductors:
        z0, z1 = cond.z * um, cond.top * um
        for net, reg in geo.wires.get(cond.name, {}).items():
            _prism(surf(net), reg, d, z0, z1, md, cuts)
            solids.append((z0, z1, reg))
    for (z0, z1), nets in (geo.vias if vias else {}).items():
        for net, reg in nets.items():
            _prism(surf(net), reg, d, z0 * um, z1 * um, md, cuts)
            solids.append((z0 * um, z1 * um, reg))
    for net, reg in geo.surface.items():
        if net != GROUND:
            _sheet(surf(net + SURF)(1e-9), reg, d, 0.0, md)
    p = fc.Problem(title="pixelkit extraction check")
    p.perm_factor = 1.0 if layered else stack.dielectric_k
    names = {}
    for (net, k), s in surfaces.items():
        p.add(s, group=s.name, outside_perm=k)
        names[f"{s.name}%{s.name}"] = net
    for (a, b, k_lo), (_a2, _b2, k_hi) in zip(layers, layers[1:]):
        if k_lo == k_hi:
            continue
        plane = sub.dup()
        for z0, z1, reg in solids:               # a conductor at or across the interface: a hole
            if z0 - 1e-6 <= b <= z1 + 1e-6:
                plane -= reg
        face = fc.Surface(name=f"interface_{b:g}")
        _sheet(face, plane, d, b, max(md, 1.0 if b < 2.0 else 2.0))
        p.add(face, kind=fc.Problem.DIELEC, outside_perm=k_hi, inside_perm=k_lo,
              r=((x0 + x1) / 2, (y0 + y1) / 2, b - 0.01), ref_point_inside=True)
    m = p.solve()
    conds = [names.get(c, c.split("%")[0]) for c in p.conductors()]
    out = {}
    for i, a in enumerate(conds):
        out[(a, a)] = m[i][i] * 1e-6          # geometry in um: the solver's F per m-unit scales by 1e-6
        for j, b in enumerate(conds):
            if j > i:
                out[(a, b) if a < b else (b, a)] = -0.5 * (m[i][j] + m[j][i]) * 1e-6
    return out


def compare(geo: NetGeometry, stack, net: str, mesh: float = 0.4e-6) -> dict:
    """The kit's and FastCap2's figures of ``net`` on ``geo``: its total wiring capacitance (to
    every other net and ground; its own diffusions' junction is the device models') and each
    coupling above 2 % of it."""
    from .capacitance import capacitances
    kit = capacitances(geo, stack)
    fcap = solve(geo, stack, mesh)
    fc_net = {}
    for (a, b), v in fcap.items():
        if a == b or net not in (a, b):
            continue
        other = (b if a == net else a).split("#")[0]
        if other != net:
            fc_net[other] = fc_net.get(other, 0.0) + v
    others = sorted(set(fc_net) | {b for k in kit.c for b in k if net in k and b != net})
    rows = [(b, kit.pair(net, b), fc_net.get(b, 0.0)) for b in others]
    total_kit = sum(r[1] for r in rows)
    total_fc = sum(r[2] for r in rows)
    return {"net": net, "total_kit_F": total_kit, "total_fastcap_F": total_fc,
            "couplings": [r for r in rows if max(r[1], r[2]) > 0.02 * total_fc]}
