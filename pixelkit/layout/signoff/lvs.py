"""The kit's own LVS: extract the layout's netlist with KLayout's Python API and compare it with
the kit's netlist of the same cell (``schematic.py``).

Extraction (``klayout.db.LayoutVsSchematic``, hierarchical), from the technology's layers by
name - the generic CMOS derivations the foundry decks make too:

- gates: poly over active; N-channel where N+ outside the n-well, P-channel where P+ inside it;
  sources / drains the rest of that active (``mos4`` devices named as the technology's
  ``nmos`` / ``pmos``, W and L in um);
- the photodiode: the n-well under the photodiode marker, one ``diode`` device whose area and
  perimeter are those of the well (the junction the models use), anode on the substrate;
- taps: P+ active outside the well ties the substrate (the global net ``vss``), N+ active in
  the well ties the well; contacts, metal1 - metal5 and the vias connect the rest; texts on the
  ``<metal>_label`` layers name nets.

The comparison (``klayout.db.NetlistComparer``) matches W and L within 1 nm and the diode's area
and perimeter within 0.1 %, and reports each mismatch by its net, device and parameter.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

from ...errors import PixelkitError
from .schematic import CELL_CIRCUIT, VSS, circuit_of, circuits_of, lvs_view, pd_device, to_klayout

METALS = ("metal1", "metal2", "metal3", "metal4", "metal5")
VIAS = ("via1", "via2", "via3", "via4")


@dataclass
class LvsResult:
    top: str
    match: bool
    seconds: float
    mismatches: list = field(default_factory=list)
    devices: int = 0
    nets: int = 0
    report: str = ""

    def as_dict(self) -> dict:
        return {"match": self.match, "top": self.top, "seconds": round(self.seconds, 2), "devices": self.devices,
                "nets": self.nets, "mismatches": self.mismatches, "report": self.report}


def _layers(lvs, layout, tech):
    import klayout.db as kdb
    out = {}

    def get(name, kind="poly"):
        lay = tech.layer(name)
        idx = layout.find_layer(lay.layer, lay.datatype)
        if idx is None:
            idx = layout.insert_layer(kdb.LayerInfo(lay.layer, lay.datatype))
        if kind == "text":
            return lvs.make_text_layer(idx, name)
        return lvs.make_polygon_layer(idx, name)

    for n in ("nwell", "active", "poly", "nplus", "pplus", "contact", "pd_marker", *METALS, *VIAS):
        out[n] = get(n)
    for n in PASSIVE_LAYERS:   # the readout's MIM capacitors and poly resistor, where the technology has them
        if n in tech.layout.layers or n in tech.layout.aliases:
            out[n] = get(n)
    for m in METALS:
        if f"{m}_label" in tech.layout.layers:
            out[f"{m}_label"] = get(f"{m}_label", "text")
    return out


def extract(lvs, layout, tech) -> dict:
    """Devices and connectivity of ``lvs`` (a LayoutVsSchematic over ``layout``); the layers it
    connected, by name (drawn and derived: ``nsd``, ``psd``, ``ptap``, ``ntap``, ``well``, ``pd_n``),
    for what reads the nets' geometry (extraction)."""
    import klayout.db as kdb
    L = _layers(lvs, layout, tech)
    nwell, active, poly = L["nwell"], L["active"], L["poly"]
    pd_n = nwell & L["pd_marker"]
    well = nwell - pd_n                                  # wells of p-channel devices
    gate = poly & active
    ngate = (gate & L["nplus"]) - nwell
    pgate = gate & L["pplus"] & well
    nsd = ((active & L["nplus"]) - nwell) - gate
    psd = ((active & L["pplus"]) & well) - gate
    ptap = ((active & L["pplus"]) - nwell) - gate
    ntap = (active & L["nplus"]) & nwell
    bulk = kdb.Region()
    pd_p = pd_n.dup()
    for name, reg in (("pd_n", pd_n), ("well", well), ("ngate", ngate), ("pgate", pgate), ("nsd", nsd),
                      ("psd", psd), ("ptap", ptap), ("ntap", ntap), ("bulk", bulk), ("pd_p", pd_p)):
        lvs.register(reg, name)
    poly, vias = _passives(lvs, L, tech, poly)
    mos = tech.mos
    lvs.extract_devices(kdb.DeviceExtractorMOS4Transistor(mos.nmos),
                        {"SD": nsd, "G": ngate, "P": poly, "W": bulk})
    lvs.extract_devices(kdb.DeviceExtractorMOS4Transistor(mos.pmos),
                        {"SD": psd, "G": pgate, "P": poly, "W": well})
    lvs.extract_devices(kdb.DeviceExtractorDiode(pd_device(tech)), {"P": pd_p, "N": pd_n})
    for r in (nsd, psd, ptap, ntap, poly, L["contact"], well, pd_n):
        lvs.connect(r)
    for a, b in (("nsd", "contact"), ("psd", "contact"), ("ptap", "contact"), ("ntap", "contact")):
        lvs.connect({"nsd": nsd, "psd": psd, "ptap": ptap, "ntap": ntap}[a], L[b])
    lvs.connect(poly, L["contact"])
    lvs.connect(well, ntap)
    lvs.connect(pd_n, ntap)
    lvs.connect(L["contact"], L["metal1"])
    for i, v in enumerate(VIAS):
        lvs.connect(L[METALS[i]], vias[v])
        lvs.connect(vias[v], L[METALS[i + 1]])
    for m in METALS:
        lvs.connect(L[m])
        if f"{m}_label" in L:
            lvs.connect(L[m], L[f"{m}_label"])
    for r in (ptap, bulk, pd_p):
        lvs.connect_global(r, VSS)
    lvs.extract_netlist()
    _mim_values(lvs.netlist(), tech)
    return {**L, "nsd": nsd, "psd": psd, "ptap": ptap, "ntap": ntap, "well": well, "pd_n": pd_n,
            "poly_conn": poly}          # the poly the connectivity holds (less a resistor's body)


#: layers of the readout's passives: MIM top plate and its marker, salicide block, resistor marker
PASSIVE_LAYERS = ("mim_top", "mim_marker", "sab", "res_marker")


def _passives(lvs, L, tech, poly):
    """The MIM capacitors (top plate under its marker over the bottom-plate metal; the vias on a
    top plate join it, not the metal below, to the metal above) and the poly resistors (poly
    under the salicide block and the resistor marker: the body, cut out of the poly that
    conducts). Returns the conducting poly and the via layers to connect."""
    import klayout.db as kdb
    vias = {v: L[v] for v in VIAS}
    pa = tech.passives
    if pa is None:
        return poly, vias
    if "mim_top" in L and "mim_marker" in L:
        top = L["mim_top"] & L["mim_marker"]
        cut = VIAS[len(METALS) - 2]                      # the via onto the top plate (via4)
        bottom_metal = L[METALS[-2]]
        on_plate, off_plate = L[cut] & L["mim_top"], L[cut] - L["mim_top"]
        bottom = bottom_metal & top
        for name, reg in (("mim_plate", top), ("mim_bottom", bottom), ("via_plate", on_plate), ("via_off", off_plate)):
            lvs.register(reg, name)
        lvs.extract_devices(kdb.DeviceExtractorCapacitor(pa.mim_lvs, pa.mim_c_area * 1e-12),
                            {"P1": bottom, "P2": top, "tA": bottom_metal, "tB": top})
        lvs.connect(top)
        lvs.connect(top, on_plate)
        lvs.connect(on_plate, L[METALS[-1]])
        vias[cut] = off_plate
    if "sab" in L and "res_marker" in L:
        body = poly & L["sab"] & L["res_marker"]
        poly = poly - body
        lvs.register(body, "res_body")
        lvs.register(poly, "poly_con")
        lvs.extract_devices(kdb.DeviceExtractorResistor(pa.res_model, pa.res_sheet), {"R": body, "C": poly})
    return poly, vias


def _mim_values(nl, tech) -> None:
    """An extracted MIM capacitor's value by the model card's law (area and perimeter terms)."""
    pa = tech.passives
    if pa is None:
        return
    import klayout.db as kdb
    dc = nl.device_class_by_name(pa.mim_lvs)
    if dc is None:
        return
    for c in nl.each_circuit():
        for d in c.each_device():
            if d.device_class().name == pa.mim_lvs:
                a, p = d.parameter(kdb.DeviceClassCapacitor.PARAM_A), d.parameter(kdb.DeviceClassCapacitor.PARAM_P)
                d.set_parameter(kdb.DeviceClassCapacitor.PARAM_C, pa.mim_c_area * a * 1e-12 + pa.mim_c_perimeter * p * 1e-6)


def _params(da, db) -> list[str]:
    diffs = []
    cls = db.device_class()
    value = [p for p in ("C", "R") if cls.has_parameter(p)]
    for p in value or ("W", "L", "A", "P"):   # a capacitor / resistor by its value, not by its shape
        if not cls.has_parameter(p):
            continue
        va, vb = da.parameter(p), db.parameter(p)
        if p in "CR":
            if abs(va - vb) > 1e-3 * abs(vb):
                unit, k = ("fF", 1e15) if p == "C" else ("Ohm", 1.0)
                diffs.append(f"{p} {va * k:.5g} {unit} (layout) vs {vb * k:.5g} {unit} (netlist)")
        elif abs(va - vb) > 1e-6 * max(1.0, abs(vb)):
            unit = "um2" if p == "A" else "um"
            diffs.append(f"{p} {va:.4g} {unit} (layout) vs {vb:.4g} {unit} (netlist)")
    return diffs


def _named(d) -> set:
    out = set()
    for t in d.device_class().terminal_definitions():
        n = d.net_for_terminal(t.id())
        if n is not None and n.name:
            out.add((t.name if t.name in ("G", "B") else "SD", n.name.lower()))   # SPICE readers upper-case
    return out


def _describe(xref) -> list[str]:
    """Mismatches from the cross reference: devices (their parameters first), nets, pins."""
    import klayout.db as kdb
    bad = (kdb.NetlistCrossReference.Mismatch, kdb.NetlistCrossReference.NoMatch)
    out = []
    for cp in xref.each_circuit_pair():
        a, b = cp.first(), cp.second()
        cname = (b or a).name if (a or b) else "?"
        if cp.status() not in bad:
            continue
        if a is None or b is None:
            out.append(f"{cname}: a circuit of the netlist with no layout cell" if a is None
                       else f"{cname}: a layout cell with no circuit in the netlist")
            continue
        extra, missing = [], []
        for dp in xref.each_device_pair(cp):
            da, db = dp.first(), dp.second()
            # paired by its nets with other sizes (the comparer warns): still a mismatch, named
            resized = dp.status() == kdb.NetlistCrossReference.MatchWithWarning and da and db and _params(da, db)
            if dp.status() not in bad and not resized:
                continue
            if da and db:
                out.append(f"{cname}: device {db.expanded_name()} ({db.device_class().name}): "
                           + ("; ".join(_params(da, db)) or "its nets differ"))
            elif db:
                missing.append(db)
            elif da:
                extra.append(da)
        for db in list(missing):   # the same device, drawn with other sizes: name the parameter
            twin = next((da for da in extra if da.device_class().name.lower() == db.device_class().name.lower()
                         and _named(da) <= _named(db) and _params(da, db)), None)
            if twin is not None:
                out.insert(0, f"{cname}: device {db.expanded_name()} ({db.device_class().name}): "
                              + "; ".join(_params(twin, db)))
                missing.remove(db)
                extra.remove(twin)
        out += [f"{cname}: device {db.expanded_name()} ({db.device_class().name}) of the netlist is missing "
                "from the layout" for db in missing]
        out += [f"{cname}: the layout has an extra {da.device_class().name} device ({_terms(da)})" for da in extra]
        for np_ in xref.each_net_pair(cp):
            if np_.status() in bad:
                na, nb = np_.first(), np_.second()
                if nb and not na:
                    out.append(f"{cname}: net {nb.expanded_name()} of the netlist has no match in the layout")
                elif na and not nb:
                    out.append(f"{cname}: layout net {na.expanded_name()} has no match in the netlist")
                elif na and nb:
                    out.append(f"{cname}: net {nb.expanded_name()} is connected differently in the layout "
                               f"(layout net {na.expanded_name()})")
        for pp in xref.each_pin_pair(cp):
            if pp.status() in bad:
                pa, pb = pp.first(), pp.second()
                out.append(f"{cname}: pin {(pb or pa).name()} unmatched (its net is open, or connected otherwise, in the layout)")
    return out


def _misnamed(xref) -> list[str]:
    """Nets the comparer paired by topology whose names differ (SPICE names are case-insensitive): a
    pin on the wrong net (two terminals' nets swapped look alike to a graph match, not to the pins'
    names)."""
    out = []
    for cp in xref.each_circuit_pair():
        a, b = cp.first(), cp.second()
        if a is None or b is None:
            continue
        for np_ in xref.each_net_pair(cp):
            na, nb = np_.first(), np_.second()
            if na is not None and nb is not None and na.name and nb.name and na.name.lower() != nb.name.lower():
                out.append(f"{b.name}: net {nb.name} of the netlist is the layout's net {na.name} "
                           "(a terminal on the wrong net)")
    return out


def _terms(d) -> str:
    return ", ".join(f"{t.name}={d.net_for_terminal(t.id()).expanded_name() if d.net_for_terminal(t.id()) else '-'}"
                     for t in d.device_class().terminal_definitions())


def prepare(lvs, ref, top: str = "", tech=None, circuit_for=circuit_of):
    """Set ``ref`` as the reference of ``lvs`` and bring both netlists to the form they are compared
    in (cells below ``top`` without a circuit of their own, ``circuit_for(cell)`` None, looked through,
    floating nets purged, top-level pins, parallel devices combined); the extracted netlist."""
    lvs.reference = ref
    nl = lvs.netlist()
    if top:
        for c in [c for c in nl.each_circuit() if c.name != top and circuit_for(c.name) is None]:
            nl.flatten_circuit(c)    # an array of references, a readout row, a shield
    nl.purge_nets()
    nl.make_top_level_pins()
    nl.combine_devices()
    ref.combine_devices()
    nl.purge()
    if tech is not None:
        _tolerances(tech, ref, nl)
    return nl


def run_lvs(gds: Path, top: str, design, workdir: Path | None = None) -> LvsResult:
    """Extract cell ``top`` of ``gds`` and compare it with the kit's netlist of that cell."""
    if circuit_of(top) is None:
        raise PixelkitError(f"no kit netlist for cell {top!r} (cells with one: {', '.join(CELL_CIRCUIT)}, "
                            "CHIP_RxC[_AFE])")
    return compare_view(gds, top, design.tech, lvs_view(design, circuits_of(design, top)), workdir, circuit_of)


def has_devices(view: list) -> bool:
    """Whether a netlist view names any device (else it is interconnect only: nets, compared by label)."""
    return any(c["mos"] or c["diodes"] or c.get("caps") or c.get("res") for c in view)


def label_nets(lvs, top: str) -> tuple[dict, list]:
    """{cluster id: name} of the nets of cell ``top`` that carry a label, and the mismatches of an
    interconnect-only netlist's nets against those labels found on the way (a net with two names: a short)."""
    names, bad = {}, []
    circuit = lvs.netlist().circuit_by_name(top)
    for net in (circuit.each_net() if circuit is not None else ()):
        if net.name:
            if "," in net.name:
                bad.append(f"{top}: nets {net.name.replace(',', ' and ')} are shorted in the layout")
            names[net.cluster_id] = net.name
    return names, bad


def compare_nets(gds: Path, top: str, tech, view: list) -> LvsResult:
    """LVS of an interconnect-only netlist (its top circuit's pins, no device): each pin must be one
    labelled net of the layout; a net with two names is a short, a name on two nets an open."""
    import klayout.db as kdb
    t0 = time.perf_counter()
    layout = kdb.Layout()
    layout.read(str(gds))
    lvs = kdb.LayoutVsSchematic(kdb.RecursiveShapeIterator(layout, layout.cell(top), []))
    extract(lvs, layout, tech)
    names, bad = label_nets(lvs, top)
    seen = {}
    for n in names.values():
        for part in n.split(","):
            seen[part.lower()] = seen.get(part.lower(), 0) + 1
    pins = [p for p in view[-1]["pins"] if p != VSS]
    bad += [f"{top}: net {p} of the netlist has no labelled shape in the layout" for p in pins if p.lower() not in seen]
    bad += [f"{top}: net {n} is open in the layout ({k} unconnected pieces carry its label)"
            for n, k in sorted(seen.items()) if k > 1]
    pin_set = {p.lower() for p in pins}
    bad += [f"{top}: layout net {n} is not a net of the netlist" for n in sorted(seen) if n not in pin_set]
    return LvsResult(top, not bad, time.perf_counter() - t0, bad, 0, len(names))


def compare_view(gds: Path, top: str, tech, view: list, workdir: Path | None = None, circuit_for=None) -> LvsResult:
    """Extract cell ``top`` of ``gds`` (hierarchically) and compare it with the netlist ``view``
    (``schematic.lvs_view``'s form). ``circuit_for(cell)``: the view's circuit a layout cell draws
    (None: looked through); by default the circuit of the same name (SPICE names are case-insensitive).
    A view without devices is compared net by net through the layout's labels (``compare_nets``)."""
    import klayout.db as kdb
    if not has_devices(view):
        return compare_nets(gds, top, tech, view)
    t0 = time.perf_counter()
    from ..gdsfile import read_klayout
    layout = read_klayout(gds, "gds")
    cell = layout.cell(top)
    if cell is None:
        raise PixelkitError(f"{gds} has no cell {top!r}")
    if circuit_for is None:
        names = {c["name"].lower(): c["name"] for c in view}

        def circuit_for(name):
            return names.get(name.lower())
    lvs = kdb.LayoutVsSchematic(kdb.RecursiveShapeIterator(layout, cell, []))
    extract(lvs, layout, tech)
    ref = to_klayout(view)
    nl = prepare(lvs, ref, top, tech, circuit_for)
    comparer = kdb.NetlistComparer()
    for c in nl.each_circuit():
        b = ref.circuit_by_name(circuit_for(c.name) or "") if c.name != top else \
            ref.circuit_by_name(circuit_for(c.name) or view[-1]["name"])
        if b is not None:
            comparer.same_circuits(c, b)
    ok = lvs.compare(comparer)
    mismatches = _describe(lvs.xref()) if not ok else []
    misnamed = _misnamed(lvs.xref())
    ok = ok and not misnamed
    mismatches += misnamed
    if not ok and not mismatches:
        mismatches = ["the netlists differ (see the report for the details)"]
    report = ""
    if workdir is not None:   # a new temporary beside it, renamed into place
        from ...fileio import atomic_target, commit
        final, tmp = atomic_target(Path(workdir) / f"{top}.lvsdb")
        lvs.write(str(tmp))
        report = str(commit(final, tmp))
    top_circuit = _circuit(nl, top)
    return LvsResult(top, ok, time.perf_counter() - t0, mismatches,
                     sum(1 for _ in top_circuit.each_device()) if top_circuit else 0,
                     sum(1 for _ in top_circuit.each_net()) if top_circuit else 0, report)


def _tolerances(tech, *netlists) -> None:
    """How close a drawn device must come to the netlist's, set on the device classes of both
    netlists (the comparer reads the tolerance of the class it meets first): W and L within
    1 nm, the photodiode's area and perimeter within 0.1 %, a capacitor's or resistor's value
    within 0.1 %."""
    import klayout.db as kdb
    eqs = []
    for model in (tech.mos.nmos, tech.mos.pmos):
        eq = kdb.EqualDeviceParameters(kdb.DeviceClassMOS4Transistor.PARAM_W, 1e-3, 0.0)
        eq += kdb.EqualDeviceParameters(kdb.DeviceClassMOS4Transistor.PARAM_L, 1e-3, 0.0)
        eqs.append((model, eq))
    eq = kdb.EqualDeviceParameters(kdb.DeviceClassDiode.PARAM_A, 0.0, 1e-3)
    eq += kdb.EqualDeviceParameters(kdb.DeviceClassDiode.PARAM_P, 0.0, 1e-3)
    eqs.append((pd_device(tech), eq))
    if tech.passives is not None:
        eqs.append((tech.passives.mim_lvs, kdb.EqualDeviceParameters(kdb.DeviceClassCapacitor.PARAM_C, 0.0, 1e-3)))
        eqs.append((tech.passives.res_model, kdb.EqualDeviceParameters(kdb.DeviceClassResistor.PARAM_R, 0.0, 1e-3)))
    for nl in netlists:
        for name, eq in eqs:
            dc = nl.device_class_by_name(name)
            if dc is not None:
                dc.equal_parameters = eq


def _circuit(nl, name):
    return nl.circuit_by_name(name)


def run_lvs_deck(gds: Path, top: str, design, workdir: Path, spice: Path) -> LvsResult:
    """The technology's own LVS deck (``[signoff] lvs_deck``, pinned by ``lvs_sha256``) on cell
    ``top`` against ``spice``, run by KLayout in batch mode (``drc.klayout_run``: a private folder,
    outputs renamed into ``workdir``); the verdict is read from the LVS database it writes (the
    cross reference of the top circuits), not from its log."""
    import klayout.db as kdb
    from .decks import lvs_deck
    from .drc import klayout_binary, klayout_run
    so = design.tech.signoff
    deck = lvs_deck(design.tech)
    exe = klayout_binary()

    def args(stage: Path) -> list[str]:
        out = [exe, "-b", "-r", str(deck), "-rd", f"input={Path(gds).resolve()}",
               "-rd", f"schematic={Path(spice).resolve()}", "-rd", f"report={stage / f'{top}.lvsdb'}",
               "-rd", f"topcell={top}", "-rd", f"target_netlist={stage / f'{top}.ext.cir'}"]
        for k, v in so.lvs_options:
            out += ["-rd", f"{k}={v}"]
        return out

    t0 = time.perf_counter()
    workdir = Path(workdir)
    _, files = klayout_run(args, workdir, {f"{top}.lvsdb": f"{top}.lvsdb", f"{top}.ext.cir": f"{top}.ext.cir",
                                           "log": f"{top}.lvs.log"}, "lvs", cwd=deck.parent)
    log = workdir / f"{top}.lvs.log"
    if f"{top}.lvsdb" not in files:
        tail = log.read_text(errors="replace").strip().splitlines()[-2:] if "log" in files else []
        raise PixelkitError(f"the LVS deck {deck.name} wrote no report: {' | '.join(tail)}; log: {log}")
    report = files[f"{top}.lvsdb"]
    db = kdb.LayoutVsSchematic()
    db.read(str(report))
    xref = db.xref()
    ok = any(cp.first() is not None and cp.first().name == top and cp.status() == kdb.NetlistCrossReference.Match
             for cp in xref.each_circuit_pair())
    return LvsResult(top, ok, time.perf_counter() - t0, [] if ok else (_describe(xref) or ["the netlists differ"]),
                     report=str(report))
