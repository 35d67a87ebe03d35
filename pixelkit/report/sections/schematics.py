"""Schematics of the generated circuits, drawn from the generated netlists (schemdraw).

Nothing here is hand-drawn: each subcircuit the generators of ``pixelkit/registry.py``
emit is walked element by element (the ``Netlist`` data objects, the same ones the
decks are written from) and every element is placed on a grid in netlist order with its
symbol (SPICE letter; ``X`` of a MOS model is drawn as a FET), its name, its model or
value and every terminal's net name. Connections are by net label (the same name is
the same node), so a generator change - an element added, removed or reconnected -
changes the picture and the element table. The golden-form netlist text of every
generator is written under ``netlists/`` (the revision diff compares it line by line).
"""
from __future__ import annotations

from pathlib import Path

from . import Checked, Figure, Section, Table

TITLE = "Schematics of the generated circuits"

#: Generators whose subcircuits are drawn (each subcircuit once, in this order).
DRAWN = ("pixel5t_primary", "dual_pixel", "sc_afe", "opamp_ota")
_COLS, _DX, _DY = 4, 6.5, 5.0
_NET = "#2856a3"


def _value_text(v) -> str:
    from ...spice.netlist import Param
    if v is None:
        return ""
    if isinstance(v, Param):
        return "{" + v.name + "}"
    if isinstance(v, float):
        return f"{v:.3g}"
    if isinstance(v, str):
        return v
    return type(v).__name__.lower()   # Pulse / Pwl


def _is_mos(e) -> bool:
    return e.name[0] in "Mm" or (e.name[0] in "Xx" and isinstance(e.value, str) and len(e.nodes) == 4
                                 and e.value.lower()[:4] in ("nfet", "pfet", "nmos", "pmos"))


def _kind(e) -> str:
    if _is_mos(e):
        return "PMOS" if e.value.lower().startswith("p") else "NMOS"
    return {"D": "diode", "C": "capacitor", "R": "resistor", "L": "inductor", "V": "voltage source",
            "I": "current source", "F": "CCCS", "H": "CCVS", "E": "VCVS", "G": "VCCS", "B": "behavioural source",
            "X": "subcircuit"}.get(e.name[0].upper(), "element")


def _nets(e) -> tuple:
    """The nets of ``e``; a current-controlled source's last 'node' is its controlling V source."""
    return e.nodes[:2] if e.name[0].upper() in "FH" else e.nodes


def _value_full(e) -> str:
    ctl = f"ctl I({e.nodes[2]}) x " if e.name[0].upper() in "FH" and len(e.nodes) > 2 else ""
    return ctl + _value_text(e.value) + _size(e)


def _size(e) -> str:
    p = dict(e.params)
    if isinstance(p.get("w"), float) and isinstance(p.get("l"), float):
        return f" {p['w'] * 1e6:.3g}/{p['l'] * 1e6:.3g}u"
    return ""


def _net(d, point, net, loc, size=7):
    import schemdraw.elements as elm
    d.add(elm.Dot(open=True, radius=0.07).at(point).label(net, loc=loc, fontsize=size, color=_NET))


def _draw_element(d, e, xy, ports_of) -> None:
    """Place element ``e`` around ``xy``; label it and the net of every terminal."""
    import schemdraw.elements as elm
    x, y = xy
    name = f"{e.name}\n{_value_text(e.value)}{_size(e)}"
    if _is_mos(e):
        cls = elm.PFet if e.value.lower().startswith("p") else elm.NFet
        f = d.add(cls().at((x, y)).anchor("center").right())
        d.add(elm.Label().at((x - 0.4, y)).label(name, fontsize=7, halign="right"))
        for anchor, net in zip(("drain", "gate", "source"), e.nodes[:3]):
            p = getattr(f, anchor)   # a PFET has its source on top
            _net(d, p, net, "right" if anchor == "gate" else ("top" if p[1] > y else "bottom"))
        d.add(elm.Label().at((x + 1.0, y - 0.9)).label(f"b={e.nodes[3]}", fontsize=6, color=_NET, halign="left"))
        return
    two = {"D": elm.Diode, "C": elm.Capacitor, "R": elm.Resistor, "L": elm.Inductor, "V": elm.SourceV,
           "I": elm.SourceI, "F": elm.SourceControlledI, "G": elm.SourceControlledI, "H": elm.SourceControlledV,
           "E": elm.SourceControlledV, "B": elm.SourceControlledV}
    letter = e.name[0].upper()
    if letter in two and len(e.nodes) >= 2:
        extra = f"\nctl {' '.join(e.nodes[2:])}" if letter in "EG" else ""
        label = f"{e.name}\n{_value_full(e)}{extra}"
        sym = two[letter]().at((x, y + 1.25)).down(2.5).label(label, loc="bottom", fontsize=7)
        c = d.add(sym.reverse() if letter in "VEH" else sym)   # '+' at the first node, as SPICE reads it
        _net(d, c.start, e.nodes[0], "top")
        _net(d, c.end, e.nodes[1], "bottom")
        return
    ports = ports_of.get(e.value) if isinstance(e.value, str) else None
    n = len(e.nodes)
    left = (n + 1) // 2
    pins = [elm.IcPin(name=(ports[i] if ports and i < len(ports) else str(i + 1)), lblsize=6,
                      side="left" if i < left else "right",
                      slot=f"{left - i}/{left}" if i < left else f"{n - i}/{n - left}", anchorname=f"t{i}")
            for i in range(n)]
    h = 0.45 * left + 0.4
    ic = d.add(elm.Ic(pins=pins, size=(2.4, h)).at((x - 1.2, y - h / 2)))
    d.add(elm.Label().at((x, y + h / 2 + 0.6)).label(name, fontsize=7))
    for i, net in enumerate(e.nodes):
        _net(d, getattr(ic, f"t{i}"), net, "left" if i < left else "right", size=6)


def draw_subckt(sub, ports_of: dict, path: Path) -> int:
    """Draw ``sub`` into the PNG ``path``; returns how many elements were drawn."""
    import schemdraw
    import schemdraw.elements as elm
    schemdraw.use("matplotlib")
    from ..figures import save
    d = schemdraw.Drawing(show=False, fontsize=8)
    d.add(elm.Label().at((0, _DY * 0.6)).label(f".subckt {sub.name}   ports: {' '.join(sub.ports)}",
                                                fontsize=9, halign="left"))
    for i, e in enumerate(sub.elements):
        _draw_element(d, e, (1.5 + (i % _COLS) * _DX, -(i // _COLS) * _DY), ports_of)
    save(d.draw(show=False).fig, path)
    return len(sub.elements)


def subcircuits(design) -> list:
    """(generator, Subckt) for every subcircuit of the drawn generators, each once."""
    from ...registry import GENERATORS
    seen, out = set(), []
    for gen in DRAWN:
        for sub in GENERATORS[gen](design).subckts:
            if sub.name not in seen:
                seen.add(sub.name)
                out.append((gen, sub))
    return out


def _netlist_files(ctx) -> tuple[list, list]:
    from ...registry import GENERATORS, golden_text
    files, rows = [], []
    for name in GENERATORS:
        text = golden_text(name, ctx.design)
        ctx.figure(f"netlists/{name}.cir").write_text(text)
        files.append(f"netlists/{name}.cir")
        rows.append([name, len([ln for ln in text.splitlines() if ln and not ln.startswith(("*", "."))])])
    return files, rows


def build(ctx) -> Section:
    files, netlist_rows = _netlist_files(ctx)
    subs = subcircuits(ctx.design)
    ports_of = {sub.name: sub.ports for _, sub in subs}
    rows, figures, checked, counts = [], [], [], []
    for i, (gen, sub) in enumerate(subs):
        ctx.progress("schematics", i, len(subs))
        fig = ctx.figure(f"schematic_{sub.name}.png")
        drawn = draw_subckt(sub, ports_of, fig)
        counts.append([sub.name, gen, len(sub.elements), drawn])
        figures.append(Figure(fig.name, f"{sub.name} (generator {gen}), drawn from the netlist: "
                                        f"{len(sub.elements)} elements; the same net label (blue) is the same node"))
        checked.append(Checked(f"schematics.{sub.name}.elements", float(len(sub.elements)), "count",
                               note="elements in the generated subcircuit"))
        rows += [[sub.name, e.name, _kind(e), _value_full(e), " ".join(_nets(e))]
                 for e in sub.elements]
    return Section(
        TITLE,
        text=["Each picture is drawn by walking the subcircuit's elements in the generated netlist (the "
              "same objects the SPICE decks are written from): every element appears with its name, its "
              "model or value (W/L in um for MOSFETs) and the net of each terminal (blue; the same name is "
              "the same node, b= is the MOSFET body). Placement is a grid in netlist order, not a "
              "hand-drawn layout, so a generator change shows here and in the element table. The netlists "
              "themselves are beside the report under netlists/ (the revision diff compares them line by line)."],
        tables=[Table("schematic_counts", "Elements per generated subcircuit (in the netlist and drawn)",
                      ["subcircuit", "generator", "elements in netlist", "elements drawn"], counts),
                Table("schematic_elements", "Every element and its nets (terminal order as in the netlist)",
                      ["subcircuit", "element", "kind", "model / value", "nets"], rows),
                Table("netlists", "Generated netlists (beside the report under netlists/)",
                      ["generator", "device lines"], netlist_rows)],
        figures=figures, files=files, checked=checked,
        data={"counts": {r[0]: {"generator": r[1], "elements": r[2], "drawn": r[3]} for r in counts}})
