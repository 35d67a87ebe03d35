"""Schematics drawn from the generated netlists (schemdraw), and the netlists themselves.

Each subcircuit of a generator is drawn from its ``Subckt`` data: one symbol per
element (MOSFET, diode, capacitor, current source, subcircuit instance as a box),
every terminal labelled with its net, so two terminals with the same label are
connected (net-label style). Nothing is hand-drawn: a changed generator changes the
picture. The golden-form netlist text of every generator is written under
``netlists/`` (the revision diff compares it line by line).
"""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import schemdraw  # noqa: E402
import schemdraw.elements as elm  # noqa: E402

from ..figures import save  # noqa: E402
from . import Figure, Section, Table  # noqa: E402

TITLE = "Schematics of the generated circuits"
DRAWN = ("pixel5t_primary", "dual_pixel", "sc_afe")
PER_ROW = 4


def _symbol(e):
    k = e.name[0].upper()
    nodes = e.nodes
    if k in ("M",) or (k == "X" and isinstance(e.value, str) and e.value.lower().startswith(("nfet", "pfet", "nmos", "pmos"))):
        pmos = isinstance(e.value, str) and "p" in e.value.lower()[:2]
        sym = (elm.PFet if pmos else elm.NFet)().label(e.name, "right", fontsize=8)
        return sym, [("drain", nodes[0]), ("gate", nodes[1]), ("source", nodes[2])]
    if k == "D":
        return elm.Diode().up().reverse().label(e.name, fontsize=8), [("start", nodes[1]), ("end", nodes[0])]
    if k == "C":
        return elm.Capacitor().up().label(e.name, fontsize=8), [("start", nodes[1]), ("end", nodes[0])]
    if k == "I":
        return elm.SourceI().up().label(e.name, fontsize=8), [("start", nodes[1]), ("end", nodes[0])]
    if k == "V":
        return elm.SourceV().up().label(e.name, fontsize=8), [("start", nodes[1]), ("end", nodes[0])]
    box = elm.Ic(pins=[elm.IcPin(name=f"{n}", side="left" if i % 2 == 0 else "right") for i, n in enumerate(nodes)],
                 size=(2.2, 0.5 * (len(nodes) // 2 + 1))).label(f"{e.name}: {e.value}", "top", fontsize=8)
    return box, []   # the pins carry the net names


def draw(subckt, path):
    with schemdraw.Drawing(show=False) as dw:
        dw.config(fontsize=8)
        for i, e in enumerate(subckt.elements):
            x, y = (i % PER_ROW) * 5.0, -(i // PER_ROW) * 5.0
            sym, pins = _symbol(e)
            dw.here = (x, y)
            placed = dw.add(sym)
            for anchor, net in pins:
                pt = getattr(placed, anchor)
                dw.add(elm.Label().at(pt).label(net, fontsize=7, color="#2856a3"))
        dw.add(elm.Label().at((0, 2.0)).label(f"{subckt.name}  ports: {' '.join(subckt.ports)}", fontsize=9, loc="right"))
        fig = dw.draw(show=False).fig
    return save(fig, path)


def build(ctx) -> Section:
    from ...circuits.registry import GENERATORS, golden_text
    d = ctx.design
    files, rows, figs = [], [], []
    for name in GENERATORS:
        text = golden_text(name, d)
        p = ctx.figure(f"netlists/{name}.cir")
        p.write_text(text)
        files.append(f"netlists/{name}.cir")
        rows.append([name, len([ln for ln in text.splitlines() if ln and not ln.startswith(("*", "."))])])
    for name in DRAWN:
        net = GENERATORS[name](d)
        sub = net.subckts[-1]
        path = draw(sub, ctx.figure(f"schematic_{name}.png"))
        figs.append(Figure(path.name, f"{sub.name} (generator {name}), drawn from the netlist; same net label = connected"))
    return Section(TITLE, text=["Drawn from the generated netlist data (net-label style); the netlists themselves "
                                "are beside the report under netlists/ (model folder written as @MODELS)."],
                   figures=figs, files=files,
                   tables=[Table("netlists", "Generated netlists", ["generator", "device lines"], rows)])
