"""Column circuitry: current-source loads of the source followers, S1X/S2X samplers and the
optional column precharge.

The load is an NMOS mirror of one bias current (the SF bias, ~400 nA in the
simulations of [Thesis2019]); each column line carries its parasitic capacitance. S1X and S2X are
transmission gates from the column to the AFE input, closed by the S1 (signal)
and S2 (reset) pulses of double sampling.
"""
from __future__ import annotations

from ..spice.netlist import Element
from ..physics.nodes import line_cap
from .devices import mosfet, tgate


def bias(design, node: str = "nbias") -> tuple:
    """The load bias: an ideal reference current into a diode-connected NMOS (node ``node``)."""
    dev = design.pixel.devices
    tag = "" if node == "nbias" else f"_{node}"
    return (Element(f"Ibias{tag}", ("vdd", node), design.pixel.sf_bias),
            mosfet(f"bias{tag}", node, node, "0", "0", dev.load_w, dev.load_l, design.tech))


def load(design, col: str, bias: str = "nbias") -> tuple:
    """Current-source load (gate on the bias node ``bias``) and parasitic capacitance of column
    line ``col``."""
    dev = design.pixel.devices
    return (mosfet(f"ld_{col}", col, bias, "0", "0", dev.load_w, dev.load_l, design.tech),
            Element(f"C{col}", (col, "0"), line_cap(design, col)))


def sampler(design, col: str, out: str, s1: str = "s1", s2: str = "s2") -> tuple:
    """S1X (signal) and S2X (reset) sampling switches from ``col`` to ``out``."""
    dev, t = design.pixel.devices, design.tech
    return (*tgate(f"s1_{col}", col, out, s1, f"{s1}b", dev.sw_w, dev.sw_l, t),
            *tgate(f"s2_{col}", col, out, s2, f"{s2}b", dev.sw_w, dev.sw_l, t))


CELL_PORTS = ("vdd", "col", "nbias", "out", "s1", "s1b", "s2", "s2b")


def precharged(design, kind: str) -> bool:
    """Array ``kind`` reads with a column precharge (its timing sets ``pre_on`` / ``pre_off``, as
    the benches' ``GsTiming.precharged`` has it)."""
    return getattr(design, kind).timing.pre_on is not None


def pre_clock(design, kind: str, name: str = "pre") -> tuple:
    """The precharge clock node ``name`` of array ``kind``, as a tuple: empty without a precharge."""
    return (name,) if precharged(design, kind) else ()


def column_cell(design, kind: str):
    """One column's circuit as a subcircuit ``column_<kind>`` (the cell the layout draws under /
    over each column line): the load bias NMOS (its reference current comes in at ``nbias``),
    the current-source load of the line, the S1X / S2X samplers to ``out`` and, when the array
    reads with one, the precharge switch (gate ``pre``, a port after ``CELL_PORTS``)."""
    from ..spice.netlist import Subckt
    pre = precharge(design, "col", "pre") if precharged(design, kind) else ()
    return Subckt(f"column_{kind}", (*CELL_PORTS, *pre_clock(design, kind)),
                  (*bias(design)[1:], *load(design, "col"), *sampler(design, "col", "out"), *pre))


def dual_pixel_column(design):
    """The dual pixel with its column circuits (``dualpix_col``): the primary's above it, one
    per secondary column under it; each array's samplers on its own clocks."""
    from ..spice.netlist import Element, Subckt
    from .dual_pixel import ports
    n = design.secondary_per_pixel
    pix = ports(n)
    pre = {"p": pre_clock(design, "primary", "pre_p"), "s": pre_clock(design, "secondary", "pre_s")}
    outer = (*pix, "nbias_p", "out_p", "s1_p", "s1b_p", "s2_p", "s2b_p", *pre["p"],
             *(f"nbias_s{k}" for k in range(n)), *(f"out_s{k}" for k in range(n)),
             "s1_s", "s1b_s", "s2_s", "s2b_s", *pre["s"])
    elems = [Element("Xpix", pix, "dualpix"),
             Element("Xcp", ("vdd", "col_p", "nbias_p", "out_p", "s1_p", "s1b_p", "s2_p", "s2b_p", *pre["p"]),
                     "column_primary")]
    for k in range(n):
        elems.append(Element(f"Xcs{k}", ("vdd", f"col_s{k}", f"nbias_s{k}", f"out_s{k}", "s1_s", "s1b_s", "s2_s",
                                          "s2b_s", *pre["s"]), "column_secondary"))
    return Subckt("dualpix_col", outer, tuple(elems))


def line_couplings(design, lines: dict, whole: bool = False) -> tuple:
    """Post-layout: the other rows' share of the couplings between the column lines of one dual pixel,
    ``lines`` mapping its lines (``col_p``, ``col_s0`` ...) to the bench's nodes (none on the schematic);
    ``whole``: every row's share (a bench whose pixels are not ``dualpix`` instances)."""
    pl = design.post_layout
    if pl is None:
        return ()
    rows = design.primary.rows
    k = rows / (rows - 1) if whole and rows > 1 else 1.0
    return tuple(Element(f"Ccc_{lines[a]}_{lines[b]}", (lines[a], lines[b]), c * k)
                 for a, b, c in pl.column_pairs if a in lines and b in lines)


def row_share(design, lines: dict, nets: dict, tag: str) -> tuple:
    """Post-layout, for a bench whose pixels are ``pix5t`` instances (the array bench): one row's
    share of the couplings ``dualpix`` carries on the dual pixel's column lines, other than those
    between the column lines (``line_couplings(whole=True)`` holds every row's share of these):
    to the row's own RS / RST lines, the global EC / TG lines, the supplies and ground. The
    dual-pixel bench has them in its ``dualpix`` instance; without them an array deck's column
    lines missed the kicks of the read row's RS / RST edges (and one row's share of the line).
    ``lines`` maps the dual pixel's column lines to the bench's nodes, ``nets`` its other lines
    (``rs_s``, ``ec_p``, ``vdd`` ...) to the bench's nodes (the row's ``rs_s_<r>`` ...); a line the
    bench does not hold (the other array's, in a deck of one array) is taken to ground.
    ``tag``: the row, for unique element names."""
    out = []
    for k, (col, other, c) in enumerate(_row_share(design)):
        if col in lines:
            out.append(Element(f"Crw{tag}_{k}_{lines[col]}", (lines[col], nets.get(other, "0")), c))
    return tuple(out)


def row_share_total(design, line: str) -> float:
    """The sum of ``row_share``'s couplings on dual-pixel column line ``line`` (``col_p``,
    ``col_s0`` ...): one row's share of the line outside the column-to-column couplings (F)."""
    return sum(c for col, _, c in _row_share(design) if col == line)


def _row_share(design) -> list:
    """(column line, other line, F) of ``dualpix``'s couplings between a column line and a line that
    is not one (empty on the schematic)."""
    pl = design.post_layout
    if pl is None:
        return []
    cols = {"col_p", *(f"col_s{k}" for k in range(design.secondary_per_pixel))}
    out = []
    for a, b, c in pl.cells.get("dualpix", ()):
        if (a in cols) != (b in cols):
            out.append((a, b, c) if a in cols else (b, a, c))
    return out


def precharge(design, col: str, ctl: str) -> tuple:
    """The column precharge: an NMOS switch (the samplers' size) from ``col`` to ground, gate
    ``ctl``: inside S1 it empties the line and C11, so the source follower then charges them
    upwards (fast) instead of the load discharging them (slow: I_load / C)."""
    dev = design.pixel.devices
    return (mosfet(f"pre_{col}", col, ctl, "0", "0", dev.sw_w, dev.sw_l, design.tech),)
