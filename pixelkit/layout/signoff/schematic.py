"""The kit's netlist of a drawn cell, as LVS sees it: the same subcircuits the simulations use
(``circuits.pixel5t`` ...), reduced to the devices a layout draws.

Kept: the MOSFETs (the technology's device names, W and L), the photodiode junction (area
and perimeter) and the subcircuit instances. Dropped, because a layout does not draw them:
ideal sources (the photocurrent ``Iph`` and its sense ``Vph``, the storage node's parasitic
light ``Fpls``, the bias reference ``Ibias``) and the lumped column-line capacitance
``C<col>`` (the wire itself is drawn; extraction puts its capacitance back). Ground ``0``
becomes the net ``vss`` (the substrate), a pin of every circuit.

Two outputs: a ``klayout.db.Netlist`` (the kit's LVS compares against it) and SPICE text
(``<cell>.spice`` beside the GDS: ``M``/``D`` cards with the PDK's names, W / L in um), which
any LVS tool - the foundry's fd_pv deck included - reads.
"""
from __future__ import annotations

from ...circuits.column import column_cell, dual_pixel_column
from ...circuits.dual_pixel import dual_pixel
from ...circuits.pixel5t import pixel5t
from ...circuits.readout import afe_cell, opamp_cell
from ...circuits.rowdriver import boosted, row_driver

VSS = "vss"


def circuits_of(design, top: str) -> list:
    """The kit's subcircuits behind layout cell ``top`` (children first)."""
    chip = _chip(top)
    if chip is not None:
        from ...circuits.array import pixel_array
        from ...circuits.readout import chip as chip_circuit, readout_cells
        rows, cols, afe = chip
        ro = readout_cells(design) if afe else [column_cell(design, "primary"), column_cell(design, "secondary")]
        drv = [row_driver(design)] if boosted(design) else []
        return [*dual_pixel(design), pixel_array(design, rows, cols), *ro, *drv, chip_circuit(design, rows, cols, afe)]
    pix = list(dual_pixel(design))                 # primary, secondary, dualpix
    col = [column_cell(design, "primary"), column_cell(design, "secondary")]
    table = {"PRIMARY": [pixel5t(design, "primary")], "SECONDARY": [pixel5t(design, "secondary")],
             "DUALPIX": pix, "COLUMN_P": col[:1], "COLUMN_S": col[1:],
             "DUALPIX_COL": [*pix, *col, dual_pixel_column(design)],
             "AFE_P": [opamp_cell(design), afe_cell(design, "primary")],
             "AFE_S": [opamp_cell(design), afe_cell(design, "secondary")],
             "ROWDRV": [row_driver(design)]}
    return table[top]


#: layout cell -> the kit's subcircuit of it
CELL_CIRCUIT = {"PRIMARY": "pix5t_primary", "SECONDARY": "pix5t_secondary", "DUALPIX": "dualpix",
                "COLUMN_P": "column_primary", "COLUMN_S": "column_secondary", "DUALPIX_COL": "dualpix_col",
                "AFE_P": "afe_primary", "AFE_S": "afe_secondary", "ROWDRV": "rowdrv"}


def _chip(cell: str):
    """(rows, cols, afe) of a chip cell name ``CHIP_RxC[_AFE]``, else None."""
    import re
    m = re.fullmatch(r"CHIP_(\d+)X(\d+)(_AFE)?", cell)
    return (int(m.group(1)), int(m.group(2)), bool(m.group(3))) if m else None


def circuit_of(cell: str) -> str | None:
    """The kit's subcircuit a layout cell draws (None: a cell LVS looks through, such as an
    array of references, a readout row or a shield)."""
    chip = _chip(cell)
    if chip is not None:
        rows, cols, afe = chip
        return f"chip_{rows}x{cols}{'_afe' if afe else ''}"
    return CELL_CIRCUIT.get(cell)


def pd_device(tech) -> str:
    """The photodiode's name in netlists for LVS: the foundry's device (its LVS deck extracts the
    junction under that name) when the technology names one, else the kit's model."""
    return tech.photodiode.foundry_card or tech.photodiode.spice_model


def _node(n: str) -> str:
    return VSS if n == "0" else n


def lvs_view(design, subckts) -> list[dict]:
    """Each subcircuit that a layout cell draws as {"name", "pins", "mos": [(name, kind, d, g, s,
    b, w_um, l_um)], "diodes": [(name, anode, cathode, model, area_um2, perim_um)], "caps":
    [(name, a, b, model, c_F, w_um, l_um)], "res": [(name, a, b, model, r_Ohm, w_um, l_um)],
    "subs": [(name, circuit, nets)]}. A subcircuit no layout cell draws on its own (the op-amp,
    drawn inside the AFE) is expanded into its parent. A capacitor between two signal nets is a
    drawn MIM capacitor (with the plate the generator draws for its value); one to ground is a
    lumped wire capacitance (dropped: the wire is drawn)."""
    by = {s.name: s for s in subckts}
    drawn = set(CELL_CIRCUIT.values())
    keep = [s for s in subckts if s.name in drawn or s is subckts[-1]]
    out = []
    for sc in keep:
        c = {"name": sc.name, "pins": [*sc.ports, VSS], "mos": [], "diodes": [], "caps": [], "res": [], "subs": []}
        _collect(design, sc, c, by, drawn, "", {p: p for p in sc.ports}, dict(sc.params))
        out.append(c)
    return out


def _collect(design, sc, c, by, drawn, prefix, nets, params) -> None:
    t = design.tech

    def n(x):
        x = _node(x)
        return nets.get(x, x if x == VSS else f"{prefix}{x}")

    def value(v):
        return params[v.name] if hasattr(v, "name") else float(v)
    for e in sc.elements:
        kind = e.name[0].upper()
        name = f"{prefix}{e.name[1:]}"
        if kind in "XM" and e.value in (t.mos.nmos, t.mos.pmos):
            p = dict(e.params)
            d, g, s_, b = (n(x) for x in e.nodes)
            c["mos"].append((name, e.value, d, g, s_, b, p["w"] * 1e6, p["l"] * 1e6))
        elif kind == "X" and e.value in by and e.value in drawn:
            c["subs"].append((name, e.value, [*(n(x) for x in e.nodes), VSS]))
        elif kind == "X" and e.value in by:          # drawn inside this cell: expanded
            inner = by[e.value]
            m = {p: n(x) for p, x in zip(inner.ports, e.nodes)}
            _collect(design, inner, c, by, drawn, f"{prefix}{e.name[1:]}_", m,
                     {**dict(inner.params), **{k: value(v) for k, v in e.params}})
        elif kind == "D":
            p = dict(e.params)
            model = pd_device(t) if e.value == t.photodiode.spice_model else e.value
            c["diodes"].append((name, n(e.nodes[0]), n(e.nodes[1]), model, p["area"] * 1e12, p["pj"] * 1e6))
        elif kind == "C" and "0" not in e.nodes and t.passives is not None:
            cval = value(e.value)
            w, l_ = _drawn(design, c["name"], "c", cval)
            c["caps"].append((name, n(e.nodes[0]), n(e.nodes[1]), t.passives.mim_lvs, cval, w, l_))
        elif kind == "R" and t.passives is not None:
            rval = value(e.value)
            w, l_ = _drawn(design, c["name"], "r", rval)
            c["res"].append((name, n(e.nodes[0]), n(e.nodes[1]), t.passives.res_model, rval, w, l_))


def _drawn(design, circuit: str, kind: str, value: float) -> tuple:
    """(W, L) in um of the plate / body the readout generator draws for this value."""
    from ..afe import drawn_size
    return drawn_size(design, circuit, kind, value)


def flat_view(view: list[dict]) -> list[dict]:
    """The top circuit of ``view`` with every subcircuit instance expanded (names ``inst.name``,
    inner nets ``inst.net``): for LVS tools that compare a flat layout."""
    by = {c["name"]: c for c in view}

    def expand(c, prefix, nets):
        mos, diodes = [], []
        m = {p: nets[i] for i, p in enumerate(c["pins"])}

        def n(x):
            return m.get(x, f"{prefix}{x}")
        for name, model, d, g, s_, b, w, l_ in c["mos"]:
            mos.append((f"{prefix}{name}", model, n(d), n(g), n(s_), n(b), w, l_))
        for name, a, k, model, area, perim in c["diodes"]:
            diodes.append((f"{prefix}{name}", n(a), n(k), model, area, perim))
        for key in ("caps", "res"):
            for name, a, b, *rest in c.get(key, ()):
                two[key].append((f"{prefix}{name}", n(a), n(b), *rest))
        for name, target, nets_ in c["subs"]:
            sm, sd = expand(by[target], f"{prefix}{name}.", [n(x) for x in nets_])
            mos += sm
            diodes += sd
        return mos, diodes
    two = {"caps": [], "res": []}
    top = view[-1]
    mos, diodes = expand(top, "", list(top["pins"]))
    clean = str.maketrans({".": "_"})
    return [{"name": top["name"], "pins": top["pins"], "subs": [],
             "mos": [(a.translate(clean), *rest[:1], *(x.translate(clean) for x in rest[1:5]), *rest[5:])
                     for a, *rest in mos],
             "diodes": [(a.translate(clean), b.translate(clean), c.translate(clean), *rest) for a, b, c, *rest in diodes],
             **{k: [(a.translate(clean), b.translate(clean), c.translate(clean), *rest) for a, b, c, *rest in v]
                for k, v in two.items()}}]


def to_klayout(view: list[dict]):
    """A ``klayout.db.Netlist`` of the view (device parameters in um / um2, KLayout's units)."""
    import klayout.db as kdb
    nl = kdb.Netlist()
    classes = {}

    def cls(name, make):
        if name not in classes:
            c = make()
            c.name = name
            nl.add(c)
            classes[name] = c
        return classes[name]

    circuits = {}
    for c in view:
        ci = kdb.Circuit()
        ci.name = c["name"]
        nl.add(ci)
        circuits[c["name"]] = ci
        nets = {}

        def net(n):
            if n not in nets:
                x = ci.create_net(n)
                nets[n] = x
            return nets[n]

        for p in c["pins"]:
            pin = ci.create_pin(p)
            ci.connect_pin(pin, net(p))
        for name, model, d, g, s, b, w, l_ in c["mos"]:
            dc = cls(model, kdb.DeviceClassMOS4Transistor)
            dev = ci.create_device(dc, name)
            for term, n in (("D", d), ("G", g), ("S", s), ("B", b)):
                dev.connect_terminal(term, net(n))
            dev.set_parameter("W", w)
            dev.set_parameter("L", l_)
        for name, anode, cathode, model, area, perim in c["diodes"]:
            dc = cls(model, kdb.DeviceClassDiode)
            dev = ci.create_device(dc, name)
            dev.connect_terminal("A", net(anode))
            dev.connect_terminal("C", net(cathode))
            dev.set_parameter("A", area)
            dev.set_parameter("P", perim)
        for key, make, param in (("caps", kdb.DeviceClassCapacitor, "C"), ("res", kdb.DeviceClassResistor, "R")):
            for name, a, b, model, value, _w, _l in c.get(key, ()):
                dc = cls(model, make)
                dev = ci.create_device(dc, name)
                dev.connect_terminal("A", net(a))
                dev.connect_terminal("B", net(b))
                dev.set_parameter(param, value)
        for name, target, nets_ in c["subs"]:
            sub = ci.create_subcircuit(circuits[target], name)
            for i, n in enumerate(nets_):
                sub.connect_pin(circuits[target].pin_by_id(i), net(n))
    return nl


def spice_text(view: list[dict], title: str) -> str:
    """The view as a SPICE netlist for LVS tools (top circuit last), each subcircuit named as the
    layout cell that draws it (LVS tools pair circuits with cells by name)."""
    cell = {v: k for k, v in CELL_CIRCUIT.items()}
    lines = [f"* {title}: the kit's netlist of the drawn devices (W, L in um; area in um2)",
             "* subcircuits named after the layout cells: " +
             ", ".join(f"{cell.get(c['name'], c['name'])} = {c['name']}" for c in view), ""]
    for c in view:
        lines.append(f".subckt {cell.get(c['name'], c['name'])} " + " ".join(c["pins"]))
        for name, model, d, g, s, b, w, l_ in c["mos"]:
            lines.append(f"M{name} {d} {g} {s} {b} {model} W={w:.6g}u L={l_:.6g}u")
        for name, anode, cathode, model, area, perim in c["diodes"]:
            lines.append(f"D{name} {anode} {cathode} {model} AREA={area:.8g}p PJ={perim:.8g}u")
        for name, a, b, model, value, w, l_ in c.get("caps", ()):   # the drawn plate: what LVS decks compare
            lines.append(f"C{name} {a} {b} {model} W={w:.6g}u L={l_:.6g}u")
        for name, a, b, model, value, w, l_ in c.get("res", ()):    # 3 terminals: the body over the substrate
            lines.append(f"R{name} {a} {b} {VSS} {model} W={w:.6g}u L={l_:.6g}u")
        for name, target, nets_ in c["subs"]:
            lines.append(f"X{name} " + " ".join(nets_) + f" {cell.get(target, target)}")
        lines.append(f".ends {cell.get(c['name'], c['name'])}")
        lines.append("")
    return "\n".join(lines) + ".end\n"
