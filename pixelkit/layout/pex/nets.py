"""The nets of a drawn cell with their geometry, matched to the kit's netlist.

The cell is flattened (labels of sub-cells dropped: only the top cell's pins name nets) and its
devices and connectivity extracted with the kit's LVS extraction (``signoff.lvs.extract``,
KLayout's ``LayoutVsSchematic``). KLayout's ``NetlistComparer`` then pairs every extracted net
with a net of the kit's flattened netlist of the same cell (``schematic.flat_view``), so each
net's geometry carries the name the simulations use (``Xp.fd``: node ``fd`` of instance ``Xp``).
A layout that does not match its netlist, or a net the comparer cannot pair, is an error that
names it: parasitics are never hung on a guessed node.

Shapes on no matched net (the top-metal shield, which the drawing leaves floating; a supply rail a
cell extracted alone leaves unjoined) are the net ``0``: a chip ties them to ground. The dummy fill of
``pixelkit layout --fill`` (the technology's ``<layer>_fill`` layers, and the kit's ``FILL_<LAYER>``
cells, whose poly lies on the drawn poly) is floating: each square a conductor of its own, a net
``~<layer>.<k>``, which ``capacitance.capacitances`` reduces away (the coupling two nets gain through a
square between them is kept).
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ...errors import PixelkitError

#: Conductors at the substrate surface (the kit's LVS layers): diffusions and wells.
SURFACE = ("nsd", "psd", "ptap", "ntap", "well", "pd_n")
GROUND = "0"
#: prefix of a floating conductor's net (dummy fill, a piece of metal on no net): its couplings are
#: reduced away after the extraction (``capacitance.float_out``), the series path through it kept
FLOATING = "~"
AFE_NODES = ("in", "out", "vref", "p1", "p1b", "p2", "p2b", "vdd", "vm", "x", "c")   # the drawn AFE's ports / nodes


@dataclass
class NetGeometry:
    """Regions (``klayout.db.Region``, dbu units) of every net on every conductor layer."""
    top: str
    dbu: float                                   # m per database unit
    wires: dict = field(default_factory=dict)    # layer -> {net: Region} (poly off the gates, metals)
    surface: dict = field(default_factory=dict)  # net -> Region (diffusions and wells)
    bbox: tuple = ()                             # the cell's extent (m)
    unmatched: list = field(default_factory=list)
    junctions: dict = field(default_factory=dict)  # surface layer (nsd, psd, well, pd_n ...) -> {net: Region}
    openings: object = None                        # Region: the drawn light openings (the kit's marker)
    cover: object = None                           # Region: metal over the cell drawn by the cells around it
    vias: dict = field(default_factory=dict)       # (z0, z1) m -> {net: Region}: the cuts between the metals
                                                   # (the field solver's; the 2.5D model leaves them out)


def _flat_names(view: list) -> tuple:
    """A netlist view's top circuit flattened as KLayout sees it, and {flat SPICE name: dotted name}."""
    from ..signoff.schematic import flat_view, to_klayout
    return to_klayout(flat_view(view)), _dotted(view)


def _dotted(view: list) -> dict:
    """{SPICE-safe flat net name ("Xpix_Xp_fd"): hierarchical name ("Xpix.Xp.fd")} of a view's top circuit."""
    by = {c["name"]: c for c in view}
    out = {}

    def walk(c, prefix, nets):
        m = {p: nets[i] for i, p in enumerate(c["pins"])}
        local = set()
        for _n, _m, *ts in c["mos"]:
            local.update(ts[:4])
        for _n, a, k, *_ in c["diodes"] + c.get("caps", []) + c.get("res", []):
            local.update((a, k))
        for name, target, nets_ in c["subs"]:
            local.update(nets_)
            walk(by[target], f"{prefix}{name}.", [m.get(x, f"{prefix}{x}") for x in nets_])
        for x in local:
            full = m.get(x, f"{prefix}{x}")
            out[full.replace(".", "_")] = full
    top_c = view[-1]
    walk(top_c, "", list(top_c["pins"]))
    return out


#: stack conductors the extraction connects under another name (the MIM's top plate: under its marker)
CONNECTED_AS = {"mim_top": "mim_plate"}


def _conductor(lvs, L, name, poly_wire):
    """The connected region of stack conductor ``name`` (None: the layout has none of it)."""
    if name == "poly":
        return poly_wire
    if name in CONNECTED_AS:
        try:
            return lvs.layer_by_name(CONNECTED_AS[name])
        except RuntimeError:      # not registered: the technology draws no such device
            return None
    return L.get(name)


def _metals(tech) -> tuple:
    """The metal levels the kit's LVS connects (a technology without a ``[stack]``: the wires the light
    model needs, by name, with no heights)."""
    from ..signoff.lvs import METALS
    return tuple(METALS)


def _flat(region):
    """A flat, merged copy (free of the extraction's deep shape store, which dies with it)."""
    import klayout.db as kdb
    out = kdb.Region()
    for p in region.each_merged():
        out.insert(p)
    return out.merged()


def net_geometry(gds, top: str, design) -> NetGeometry:
    """Flatten ``top`` of ``gds``, extract and match its nets with the kit's netlist of that cell; their
    geometry by layer."""
    from ..signoff.schematic import circuits_of, lvs_view
    return view_geometry(gds, top, design.tech, lvs_view(design, circuits_of(design, top)))


def view_geometry(gds, top: str, tech, view: list) -> NetGeometry:
    """Flatten ``top`` of ``gds``, extract its nets and pair each with a net of ``view``'s top circuit
    (``schematic.lvs_view``'s form: the kit's netlists, or a designer's read by ``signoff.netlist_in``);
    their geometry by layer."""
    import klayout.db as kdb
    from ..gdsfile import read_klayout
    from ..signoff.lvs import extract, has_devices, label_nets, prepare
    layout = read_klayout(gds, "gds")
    cell = layout.cell(top)
    if cell is None:
        raise PixelkitError(f"{gds} has no cell {top!r}")
    for ci in cell.called_cells():
        sub = layout.cell(ci)
        for li in layout.layer_indexes():
            for s in list(sub.shapes(li).each(kdb.Shapes.STexts)):
                sub.shapes(li).erase(s)
    fill = _fill_cells(layout, cell, tech)
    cell.flatten(-1, True)
    lvs = kdb.LayoutVsSchematic(kdb.RecursiveShapeIterator(layout, cell, []))
    L = extract(lvs, layout, tech)
    L["fill_cells"] = fill
    if not has_devices(view):         # interconnect only: the nets are the labels (signoff.lvs.compare_nets)
        names, bad = label_nets(lvs, top)
        if bad:
            raise PixelkitError(f"extraction of {top}: " + "; ".join(bad[:5]))
        return _geometry(lvs, L, layout, cell, top, tech, lvs.netlist(), names)
    ref, dotted = _flat_names(view)
    nl = prepare(lvs, ref, tech=tech)
    comparer = kdb.NetlistComparer()
    a, b = nl.circuit_by_name(top), next(ref.each_circuit_top_down())
    if a is not None:
        comparer.same_circuits(a, b)
    ok = lvs.compare(comparer)
    xref = lvs.xref()
    if not ok:
        from ..signoff.lvs import _describe
        raise PixelkitError(f"extraction of {top}: the layout does not match the kit's netlist, so its parasitics "
                            "cannot be placed: " + "; ".join(_describe(xref)[:5]))
    names, unmatched = {}, []
    for cp in xref.each_circuit_pair():
        for np_ in xref.each_net_pair(cp):
            na, nb = np_.first(), np_.second()
            if na is not None and nb is not None:
                names[na.cluster_id] = dotted.get(nb.name, nb.name)
            elif na is not None:
                unmatched.append(na.expanded_name())
    if unmatched:
        raise PixelkitError(f"extraction of {top}: layout net(s) {', '.join(sorted(unmatched))} match no net of "
                            "the kit's netlist")
    return _geometry(lvs, L, layout, cell, top, tech, nl, names)


def _geometry(lvs, L, layout, cell, top, tech, nl, names) -> NetGeometry:
    """Each named net's shapes by conductor layer (``names``: {cluster id: name}); the rest ground."""
    import klayout.db as kdb
    stack = tech.stack
    conductors = stack.names() if stack is not None else ("poly", *_metals(tech))
    dbu = layout.dbu * 1e-6
    geo = NetGeometry(top, dbu)
    circuit = nl.circuit_by_name(top) or next(nl.each_circuit_top_down())
    # the gates are the devices' (their capacitance is the models'); the poly is the connectivity's (a resistor's
    # body taken out: with the readout's passives drawn it is another layer object than the drawn poly, and
    # the nets' poly read from the drawn one came back empty - every poly wire went to ground, before)
    poly_wire = L["poly_conn"] - L["active"]
    layers = {name: _conductor(lvs, L, name, poly_wire) for name in conductors}
    layers = {k: v for k, v in layers.items() if v is not None}
    claimed = {name: kdb.Region() for name in layers}
    for net in circuit.each_net():
        name = names.get(net.cluster_id)
        if name is None:
            continue
        for lname, reg in layers.items():
            r = lvs.shapes_of_net(net, L["poly_conn"], True) - L["active"] if lname == "poly" else \
                lvs.shapes_of_net(net, reg, True)
            r = _flat(r)
            if not r.is_empty():
                geo.wires.setdefault(lname, {})
                geo.wires[lname][name] = geo.wires[lname].get(name, kdb.Region()) + r
                claimed[lname] += r
        surf = kdb.Region()
        for s in SURFACE:
            part = lvs.shapes_of_net(net, L[s], True)
            surf += part
            part = _flat(part)
            if not part.is_empty():
                geo.junctions.setdefault(s, {})[name] = part
        surf = _flat(surf)
        if not surf.is_empty():
            geo.surface[name] = geo.surface.get(name, kdb.Region()) + surf
    for lname, reg in layers.items():
        rest = _flat(reg - claimed[lname])
        fill = L["fill_cells"].get(lname, kdb.Region())
        floating = (rest & fill) + _fill(layout, cell, tech, lname)
        rest = rest - fill
        if not rest.is_empty():      # the shield, a supply rail joined outside the cell: ground
            geo.wires.setdefault(lname, {})
            geo.wires[lname][GROUND] = geo.wires[lname].get(GROUND, kdb.Region()) + rest
        for k, p in enumerate(floating.merged().each()):   # dummy fill: each square its own, floating net
            geo.wires.setdefault(lname, {})[f"{FLOATING}{lname}.{k}"] = kdb.Region(p)
    if "opening" in tech.layout.layers or "opening" in tech.layout.aliases:
        lay = tech.layer("opening")
        idx = layout.find_layer(lay.layer, lay.datatype)
        geo.openings = _flat(kdb.Region(cell.begin_shapes_rec(idx))) if idx is not None else kdb.Region()
    if stack is not None:
        _vias(geo, lvs, L, circuit, names, stack)
    b = cell.bbox()
    geo.bbox = (b.left * dbu, b.bottom * dbu, b.right * dbu, b.top * dbu)
    return geo


def _fill_cells(layout, cell, tech) -> dict:
    """{conductor: Region} of the kit's fill cells under ``cell`` (``FILL_<LAYER>``: ``layout/fill.py``'s
    squares, placed in its ``<chip>_FILL``), in ``cell``'s coordinates: poly fill lies on the drawn poly
    layer (the density deck counts only that), so it is known by its cell."""
    import klayout.db as kdb
    out = {}
    for c in layout.each_cell():
        if not c.name.startswith("FILL_"):
            continue
        lname = c.name[len("FILL_"):].lower()
        if lname not in tech.layout.layers:
            continue
        lay = tech.layer(lname)
        idx = layout.find_layer(lay.layer, lay.datatype)
        if idx is None:
            continue
        reg = kdb.Region()
        inst = cell.begin_instances_rec()
        inst.targets = [c.cell_index()]
        while not inst.at_end():
            reg.insert(kdb.Region(c.begin_shapes_rec(idx)).transformed(inst.trans() * inst.inst_trans()))
            inst.next()
        if not reg.is_empty():
            out[lname] = reg.merged()
    return out


def _fill(layout, cell, tech, lname: str):
    """The dummy fill of conductor ``lname`` (the technology's ``<lname>_fill`` layer), flattened."""
    import klayout.db as kdb
    name = f"{lname}_fill"
    if name not in tech.layout.layers:
        return kdb.Region()
    lay = tech.layer(name)
    idx = layout.find_layer(lay.layer, lay.datatype)
    return _flat(kdb.Region(cell.begin_shapes_rec(idx))) if idx is not None else kdb.Region()


def _vias(geo, lvs, L, circuit, names, stack) -> None:
    """Each named net's vias, at the heights between the metals they join (``geo.vias``)."""
    from ..signoff.lvs import METALS, VIAS
    names_in = set(stack.names())
    for k, via in enumerate(VIAS):
        lo, hi = METALS[k], METALS[k + 1]
        if via not in L or lo not in names_in or hi not in names_in:
            continue
        z0, z1 = stack.conductor(lo).top, stack.conductor(hi).z
        for net in circuit.each_net():
            name = names.get(net.cluster_id)
            if name is None:
                continue
            r = _flat(lvs.shapes_of_net(net, L[via], True))
            if not r.is_empty():
                geo.vias.setdefault((z0, z1), {})[name] = r
