"""The independent check of the extraction: FastCap2 (a 3D boundary-element capacitance solver,
pip ``fastcap2``) on the same geometry.

Every net's shapes become closed conductors: each merged polygon of a layer extruded from the
stack's z to z + thickness (faces split into rectangles, meshed), diffusions and wells as sheets
in the substrate's plane (z = 0), the substrate a ground sheet around them reaching beyond the
window by the stack's height, the shield (net ``0``) on that ground. One uniform dielectric (the stack's k).
Vias are left out (their area is < 1 % of the wires'). FastCap2 returns the Maxwell matrix;
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
    return replace(geo, wires=wires, surface=surface, bbox=tuple(window))


def _quad(surf, p0, p1, p2, md):
    """A meshed rectangle p0, p1, p2 (corner, its two neighbours), the rim finer when it is large."""
    import math
    a, b = math.dist(p0, p1), math.dist(p0, p2)
    if min(a, b) > 4 * EDGE:
        surf.add_meshed_quad(p0, p1, p2, max_dim=md, edge_width=EDGE)
    else:
        surf.add_meshed_quad(p0, p1, p2, max_dim=md)


def _prism(surf, reg, d, z0, z1, md):
    """The closed surface of ``reg`` extruded from z0 to z1: top and bottom faces as rectangles, the
    walls along the merged outlines only (no face inside the conductor)."""
    import klayout.db as kdb
    for p in reg.merged().each():
        for t in p.decompose_trapezoids(kdb.Polygon.TD_htrapezoids):
            b = t.bbox()
            for z in (z0, z1):
                _quad(surf, (b.left * d, b.bottom * d, z), (b.right * d, b.bottom * d, z),
                                     (b.left * d, b.top * d, z), md)
        for e in p.each_edge():
            _quad(surf, (e.p1.x * d, e.p1.y * d, z0), (e.p2.x * d, e.p2.y * d, z0),
                                 (e.p1.x * d, e.p1.y * d, z1), md)


def _sheet(surf, reg, d, z, md):
    """``reg`` as a conductor sheet of no thickness at height z (the substrate surface)."""
    import klayout.db as kdb
    for p in reg.merged().each():
        for t in p.decompose_trapezoids(kdb.Polygon.TD_htrapezoids):
            b = t.bbox()
            _quad(surf, (b.left * d, b.bottom * d, z), (b.right * d, b.bottom * d, z),
                                 (b.left * d, b.top * d, z), md)


def solve(geo: NetGeometry, stack, mesh: float = 0.4e-6, sub_margin: float | None = None) -> dict:
    """{(a, b): coupling F, (a, a): total F} of every net of ``geo`` by FastCap2 (lengths in um inside)."""
    import fastcap2 as fc
    import klayout.db as kdb
    um = 1e6
    d = geo.dbu * um
    x0, y0, x1, y1 = (v * um for v in geo.bbox)
    margin = (stack.conductors[-1].top * um) if sub_margin is None else sub_margin * um
    md = mesh * um
    surfaces = {}

    def surf(net):
        if net not in surfaces:
            surfaces[net] = fc.Surface(name=net.replace(".", "_").replace("#", "_") or "x")
        return surfaces[net]
    sub = kdb.Region(kdb.Box(*(int(round(v / d)) for v in (x0 - margin, y0 - margin, x1 + margin, y1 + margin))))
    islands = kdb.Region()
    for reg in geo.surface.values():
        islands += reg
    _sheet(surf(GROUND), sub - islands.sized(GAP), d, 0.0, max(md, 1.0))
    for cond in stack.conductors:
        z0, z1 = cond.z * um, cond.top * um
        for net, reg in geo.wires.get(cond.name, {}).items():
            _prism(surf(net), reg, d, z0, z1, md)
    for net, reg in geo.surface.items():
        if net != GROUND:
            _sheet(surf(net + SURF), reg, d, 0.0, md)
    p = fc.Problem(title="pixelkit extraction check")
    p.perm_factor = stack.dielectric_k
    names = {}
    for net, s in surfaces.items():
        p.add(s)
        names[s.name] = net
    m = p.solve()
    conds = [names[c.split("%")[0]] for c in p.conductors()]
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
