"""Test structures for the extraction, one capacitance term each, in a GDS with labelled nets.

None of them is a geometry a constant of the 2.5D model was set on (those are listed in
docs/post-layout.md: a metal1 line pair 0.23 um wide, 10 um long, 0.23 / 0.5 / 1.0 um apart for the
fringe shielding; a metal1 / metal2 line pair 0.23 / 0.38 um wide for the corner field's KAPPA). Each
structure stands alone, 30 um from the next (more than the stack's 8 um halo), on the technology's own
layers, its nets named by labels on their metal:

| structure | nets | term |
|---|---|---|
| ``plate_sub`` | a 20 x 20 um metal1 plate ``ps`` | plate to substrate (area and its fringe) |
| ``plate_plate`` | a 10 x 10 um metal2 plate ``pt`` centred over a 20 x 20 um metal1 plate ``pb`` | plate over plate |
| ``lateral_<s>`` | two metal1 lines 0.5 x 50 um ``la<s>``, ``lb<s>``, s = 0.25, 0.5, 1, 2, 3.2 um apart | lateral coupling |
| ``fringe`` | a metal3 line 0.5 x 40 um ``fl`` over a 20 x 50 um metal1 plate ``fp`` | fringe to a plane (the coupling less its plate term) |
| ``top_line`` | a metal5 line 1 x 40 um ``tl`` | top metal to substrate (its top face under the passivation, then air) |
| ``crossing`` | a metal1 line ``xa`` (0.5 x 20 um, along x) under a metal2 line ``xb`` (along y) | crossing |
| ``via_stack`` | two 1 x 1 um metal1 - metal5 pad stacks joined by 2 x 2 vias, ``va``, ``vb``, 1 um apart | via stack to via stack |

``write(tech, folder)`` writes ``structures.gds`` and ``structures.spice`` (one subcircuit, its pins the
nets, no device) for ``pixelkit signoff``; ``STRUCTURES`` gives each one's window and nets.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

PITCH = 80.0        # um between structures' origins (each < 50 um: > 30 um apart)
SPACINGS = (0.25, 0.5, 1.0, 2.0, 3.2)


@dataclass(frozen=True)
class Structure:
    name: str
    pair: tuple          # the two nets whose coupling is the term ((net, "0"): to ground)
    term: str
    shapes: tuple        # (layer name, x0, y0, x1, y1 um, net)
    window: tuple = ()   # x0, y0, x1, y1 um (set by _placed)


def _vias(tech, x, y, net):
    """A 1 x 1 um pad stack metal1 - metal5 at (x, y) with a 2 x 2 array of each via."""
    from ..techview import LayoutTech
    lt = LayoutTech(tech)
    out = [(m, x, y, x + 1.0, y + 1.0, net) for m in ("metal1", "metal2", "metal3", "metal4", "metal5")]
    for v in ("via1", "via2", "via3", "via4"):
        cut, space = lt.cut(v) / 1000, max(lt.nm(f"{v}.space") / 1000, 0.26)
        x0 = x + (1.0 - 2 * cut - space) / 2
        for i in range(2):
            for j in range(2):
                cx, cy = x0 + i * (cut + space), x0 - x + y + j * (cut + space)
                out.append((v, cx, cy, cx + cut, cy + cut, net))
    return out


def structures(tech) -> list:
    """The structures of the module's table, placed along x."""
    items = [Structure("plate_sub", ("ps", "0"), "plate to substrate",
                       (("metal1", 0, 0, 20, 20, "ps"),)),
             Structure("plate_plate", ("pb", "pt"), "plate over plate",
                       (("metal1", 0, 0, 20, 20, "pb"), ("metal2", 5, 5, 15, 15, "pt")))]
    for s in SPACINGS:
        tag = f"{s:g}".replace(".", "p")
        items.append(Structure(f"lateral_{tag}", (f"la{tag}", f"lb{tag}"), f"lateral coupling, {s:g} um apart",
                               (("metal1", 0, 0, 50, 0.5, f"la{tag}"), ("metal1", 0, 0.5 + s, 50, 1.0 + s, f"lb{tag}"))))
    items += [Structure("fringe", ("fl", "fp"), "fringe to a plane",
                        (("metal1", 0, 0, 50, 20, "fp"), ("metal3", 5, 9.75, 45, 10.25, "fl"))),
              Structure("top_line", ("tl", "0"), "top metal line to substrate (under the passivation and air)",
                        (("metal5", 0, 0, 40, 1.0, "tl"),)),
              Structure("crossing", ("xa", "xb"), "crossing",
                        (("metal1", 0, 9.75, 20, 10.25, "xa"), ("metal2", 9.75, 0, 10.25, 20, "xb"))),
              Structure("via_stack", ("va", "vb"), "via stack to via stack",
                        tuple(_vias(tech, 0, 0, "va") + _vias(tech, 2.0, 0, "vb")))]
    out = []
    for k, st in enumerate(items):
        dx = k * PITCH
        shapes = tuple((lay, x0 + dx, y0, x1 + dx, y1, n) for lay, x0, y0, x1, y1, n in st.shapes)
        xs = [v for s in shapes for v in (s[1], s[3])]
        ys = [v for s in shapes for v in (s[2], s[4])]
        out.append(Structure(st.name, st.pair, st.term, shapes, (min(xs), min(ys), max(xs), max(ys))))
    return out


def write(tech, folder: Path) -> tuple[Path, Path]:
    """``structures.gds`` (cell STRUCTURES) and ``structures.spice`` in ``folder``."""
    import gdstk
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    cell = gdstk.Cell("STRUCTURES")
    nets = []
    for st in structures(tech):
        labelled = set()
        for lay, x0, y0, x1, y1, net in st.shapes:
            ly = tech.layer(lay)
            cell.add(gdstk.rectangle((x0, y0), (x1, y1), layer=ly.layer, datatype=ly.datatype))
            if lay.startswith("metal") and net not in labelled:
                lb = tech.layer(f"{lay}_label")
                cell.add(gdstk.Label(net, ((x0 + x1) / 2, (y0 + y1) / 2), layer=lb.layer, texttype=lb.datatype))
                labelled.add(net)
                nets.append(net)
    lib.add(cell)
    gds = folder / "structures.gds"
    lib.write_gds(str(gds))
    spice = folder / "structures.spice"
    spice.write_text("* extraction test structures (pixelkit.layout.pex.structures): nets only, no device\n"
                     f".subckt STRUCTURES {' '.join(dict.fromkeys(nets))}\n.ends STRUCTURES\n.end\n")
    return gds, spice


def geometry(tech, folder: Path):
    """The structures written to ``folder`` and their nets' geometry (``nets.view_geometry``, named by the
    labels), as ``pixelkit signoff`` extracts them."""
    from ..signoff.netlist_in import read_netlist
    from .nets import view_geometry
    gds, spice = write(tech, folder)
    return view_geometry(gds, "STRUCTURES", tech, read_netlist(spice, tech).top_view("STRUCTURES"))


def term(couplings, st: Structure) -> float:
    """A structure's term from a ``{(a, b): F}`` table or a ``Couplings``: the pair's coupling, or the net's
    total when its other end is ground."""
    a, b = st.pair
    get = couplings.pair if hasattr(couplings, "pair") else (lambda x, y: couplings.get(tuple(sorted((x, y))), 0.0))
    if b == "0":
        if hasattr(couplings, "total"):
            return couplings.total(a)
        return couplings[(a, a)]
    return get(a, b)


MARGIN = 10e-6     # the window FastCap2 solves round each structure (m)


def fastcap_reference(tech, folder: Path, mesh: float = 0.5e-6) -> dict:
    """{structure: F} by FastCap2 on the technology's stack (its layered dielectrics), each structure in a
    window MARGIN beyond it; a net's term to ground is its total (the substrate sheet and the space round
    it). The via stack with its vias."""
    from .fastcap import clip, solve
    geo = geometry(tech, folder)
    out = {}
    for st in structures(tech):
        x0, y0, x1, y1 = st.window
        g = clip(geo, (x0 * 1e-6 - MARGIN, y0 * 1e-6 - MARGIN, x1 * 1e-6 + MARGIN, y1 * 1e-6 + MARGIN))
        out[st.name] = term(solve(g, tech.stack, mesh, vias=st.name == "via_stack"), st)
    return out


def kit_terms(tech, geo, stack=None) -> dict:
    """{structure: F} by the kit's 2.5D model (``capacitance.capacitances``) on the same windows."""
    from .capacitance import capacitances
    from .fastcap import clip
    out = {}
    for st in structures(tech):
        x0, y0, x1, y1 = st.window
        g = clip(geo, (x0 * 1e-6 - MARGIN, y0 * 1e-6 - MARGIN, x1 * 1e-6 + MARGIN, y1 * 1e-6 + MARGIN))
        out[st.name] = term(capacitances(g, stack or tech.stack), st)
    return out


if __name__ == "__main__":      # python -m pixelkit.layout.pex.structures OUT.json: the FastCap2 reference
    import json
    import sys
    import tempfile
    from ...tech.technology import load_technology
    t = load_technology("gf180mcu_3v3")
    with tempfile.TemporaryDirectory() as tmp:
        ref = fastcap_reference(t, Path(tmp))
    Path(sys.argv[1]).write_text(json.dumps({"technology": t.name, "stack": t.stack.source, "mesh_um": 0.5,
                                             "margin_um": MARGIN * 1e6, "solver": "fastcap2 (pip), layered dielectrics",
                                             "terms_F": ref}, indent=1) + "\n")
