"""Xschem schematics drawn from the kit's netlists: a pixel's subcircuit or a whole bench, read back by Xschem.

``write_xschem`` draws each element as a symbol (a MOSFET for M and for X instances of a 4-terminal
``*fet*`` / ``*mos*`` model, a capacitor, resistor, diode or source for two-terminal elements, a box
with numbered pins otherwise) whose pins end in a short wire and a net label (``devices/lab_pin``):
Xschem connects every pin of one net through its labels, so the drawing *is* the circuit, not a grid
of loose elements. The subcircuit's ports are ``devices/iopin`` pins. Each symbol's SPICE line is
``@name @pinlist @value``: ``value`` carries the rest of the element's line (model, value,
parameters, a behavioural expression) as the kit writes it, so Xschem's netlist of the drawing
repeats the kit's element lines. Everything of a deck that is not an element (model includes and
cards, subcircuit definitions, options, temperature, analysis) goes into one ``devices/code`` block:
Xschem's netlist of a drawn bench runs in ngspice as it is.

The symbols (``pk_*.sym``) are written beside the schematic: Xschem finds them when that folder is on
its ``XSCHEM_LIBRARY_PATH`` (``append XSCHEM_LIBRARY_PATH :<folder>`` in an xschemrc); the net labels,
pins and code block are Xschem's own ``devices`` library. ``tests/test_schematic.py`` netlists the
drawings with Xschem itself (the independent reader) and compares.
"""
from __future__ import annotations

import re
from pathlib import Path

from ..errors import ConfigError
from ..fileio import write_atomic

#: the drawing's columns (Xschem units): pitch, height filled before the next column, gap between symbols
DX, HEIGHT, GAP = 280, 1000, 120
#: wire stub from a pin to its label
STUB = 20
_MOS_MODEL = re.compile(r"(fet|mos)", re.I)


def _esc(text: str) -> str:
    """An Xschem attribute value (between double quotes): a quote as ``\\\\"``, braces as ``\\{`` ``\\}``
    (what Xschem 2.8.1 reads back as the characters; a backslash has no such form and is refused)."""
    if "\\" in text:
        raise ConfigError("", "schematic text", text[:60], "no backslash (Xschem attributes cannot carry one)")
    return text.replace("{", "\\{").replace("}", "\\}").replace('"', '\\\\"')


def _line(kind: int, *xy) -> str:
    return f"L {kind} " + " ".join(f"{v:g}" for v in xy) + " {}"


def _pin(name: str, x: float, y: float) -> str:
    return f"B 5 {x - 2.5:g} {y - 2.5:g} {x + 2.5:g} {y + 2.5:g} {{name={name} dir=inout}}"


#: symbol -> (pins ((name, x, y, stub direction dx, dy), ...), drawing lines)
def _mos_symbol():
    pins = (("d", 20, -40, 0, -1), ("g", -40, 0, -1, 0), ("s", 20, 40, 0, 1), ("b", 40, 0, 1, 0))
    art = [_line(4, 20, -40, 20, -20), _line(4, 5, -20, 20, -20), _line(4, 5, -30, 5, 30), _line(4, 5, 20, 20, 20),
           _line(4, 20, 20, 20, 40), _line(4, -5, -15, -5, 15), _line(4, -40, 0, -5, 0), _line(4, 5, 0, 40, 0)]
    return pins, art


def _two_symbol(letter: str):
    pins = (("p", 0, -40, 0, -1), ("n", 0, 40, 0, 1))
    art = [_line(4, 0, -40, 0, -12), _line(4, 0, 12, 0, 40)]
    if letter == "C":
        art += [_line(4, -15, -5, 15, -5), _line(4, -15, 5, 15, 5), _line(4, 0, -12, 0, -5), _line(4, 0, 5, 0, 12)]
    elif letter == "D":
        art += [_line(4, -12, -12, 12, -12), _line(4, -12, -12, 0, 10), _line(4, 12, -12, 0, 10),
                _line(4, -12, 10, 12, 10), _line(4, 0, 10, 0, 12)]
    elif letter in "RL":
        art += [_line(4, -6, -12, 6, -12), _line(4, 6, -12, 6, 12), _line(4, 6, 12, -6, 12), _line(4, -6, 12, -6, -12)]
    else:   # sources: a circle (drawn as an octagon), the arrow of the current
        r = 12
        pts = [(r * c, r * s) for c, s in ((1, 0), (.7, .7), (0, 1), (-.7, .7), (-1, 0), (-.7, -.7), (0, -1), (.7, -.7), (1, 0))]
        art += [_line(4, *a, *b) for a, b in zip(pts, pts[1:])]
        art += [_line(4, 0, -8, 0, 8), _line(4, -4, 4, 0, 8), _line(4, 4, 4, 0, 8)]
    return pins, art


def _box_symbol(n: int):
    pins = tuple((f"n{i + 1}", -40, 20 * i, -1, 0) for i in range(n))
    h = 20 * (n - 1)
    art = [_line(4, -20, -10, 20, -10), _line(4, 20, -10, 20, h + 10), _line(4, 20, h + 10, -20, h + 10),
           _line(4, -20, h + 10, -20, -10), *(_line(4, -40, 20 * i, -20, 20 * i) for i in range(n))]
    return pins, art


def _shape(e) -> tuple[str, tuple, list]:
    letter, n = e.name[0].upper(), len(e.nodes)
    model = e.value if isinstance(e.value, str) else ""
    if n == 4 and (letter == "M" or (letter == "X" and _MOS_MODEL.search(model))):
        return "pk_mos", *_mos_symbol()
    if n == 2:
        return f"pk_{letter.lower()}2", *_two_symbol(letter)
    return f"pk_box{n}", *_box_symbol(n)


def _symbol_text(pins, art) -> str:
    return "\n".join(['G {type=primitive', 'format="@name @pinlist @value"', 'template="name=X1 value=1"}', "V {}", "S {}",
                      *art, *(_pin(p, x, y) for p, x, y, _dx, _dy in pins),
                      "T {@name} 25 -35 0 0 0.2 0.2 {}", "T {@value} 25 22 0 0 0.12 0.12 {}"]) + "\n"


def element_rest(e) -> str:
    """The element's line after its name and nodes (what the symbol's ``value`` carries)."""
    text = e.text()
    head = " ".join([e.name, *e.nodes])
    if not text.startswith(head):
        raise ValueError(f"{e.name}: its line does not start with its name and nodes")
    return text[len(head):].strip()


def write_xschem(path, ports, elements, code: str = "") -> Path:
    """Draw ``elements`` (with ``ports`` as the schematic's pins and ``code`` in a code block) as the Xschem
    schematic ``path`` (``.sch``); the ``pk_*.sym`` symbols it uses are written beside it."""
    path = Path(path)
    if path.suffix != ".sch":
        raise ConfigError("", "--schematic", str(path), "an Xschem schematic file name ending in .sch")
    path.parent.mkdir(parents=True, exist_ok=True)
    out, symbols, labels = ["v {xschem version=2.8.1 file_version=1.1}", "G {}", "V {}", "S {}", "E {}"], {}, 0
    for i, port in enumerate(ports):
        out.append(f"C {{devices/iopin}} -200 {40 * i} 0 0 {{name=p{i + 1} lab={port}}}")
    x0, y0 = 0, 0
    for e in elements:
        sym, pins, art = _shape(e)
        symbols[sym] = _symbol_text(pins, art)
        top, bottom = min(py for _p, _x, py, _dx, _dy in pins), max(py for _p, _x, py, _dx, _dy in pins)
        if y0 > 0 and y0 + bottom - top + 2 * STUB > HEIGHT:   # this symbol's pins and stubs would pass the column
            x0, y0 = x0 + DX, 0
        y0 += STUB - top   # the symbol's highest stub end lands at the cursor
        out.append(f'C {{{sym}}} {x0} {y0} 0 0 {{name={e.name} value="{_esc(element_rest(e))}"}}')
        for (_p, px, py, dx, dy), net in zip(pins, e.nodes):
            ax, ay, bx, by = x0 + px, y0 + py, x0 + px + STUB * dx, y0 + py + STUB * dy
            labels += 1
            out.append(f"N {ax} {ay} {bx} {by} {{lab={net}}}")
            out.append(f"C {{devices/lab_pin}} {bx} {by} 0 {1 if dx > 0 else 0} {{name=l{labels} lab={net}}}")
        y0 += bottom + STUB + GAP
    if code.strip():
        x = x0 + DX
        out.append(f'C {{devices/code}} {x} 0 0 0 {{name=kit only_toplevel=false value="{_esc(code.strip())}"}}')
    for sym, text in symbols.items():
        write_atomic(path.parent / f"{sym}.sym", text)
    write_atomic(path, "\n".join(out) + "\n")
    return path


def subckt_schematic(subckt, path, support=(), models=()) -> Path:
    """The subcircuit ``subckt`` drawn (its ports as pins; in the code block its own ``.model`` cards, the
    deck-level ``models`` it uses (a designer's netlist's) and the subcircuits ``support`` it instantiates;
    the technology's model library is the designer's tools')."""
    cards = [ln for ln in subckt.text().splitlines() if ln.startswith(".model ")] + [m.text() for m in models]
    return write_xschem(path, subckt.ports, subckt.elements, "\n".join([*cards, *(s.text() for s in support)]))


def deck_schematic(net, text: str, path) -> Path:
    """A bench ``net`` drawn: its top-level elements as symbols, every other line of its deck ``text`` (the
    exported deck: includes, models, subcircuits, options, analysis; not the title) in the code block."""
    own = {e.text() for e in net.elements}
    lines = text.splitlines()
    body = [ln for ln in lines[1:] if ln not in own and not ln.startswith("* ") and ln.strip() != ".end"]
    missing = own - set(lines)
    if missing:
        raise ValueError(f"element lines not found in the deck text: {sorted(missing)[:3]}")
    return write_xschem(path, (), net.elements, "\n".join(body))
