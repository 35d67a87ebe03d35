"""Read chains in a deck: the dual-pixel bench's, and the gap surrogate's packed benches.

A *chain* is one subpixel read through its column: the pixel, the column load and line, the
precharge, S1X / S2X and the SC AFE. The dual-pixel bench (``circuits.testbench.dual_pixel_bench``)
holds one primary chain and ``secondary_per_pixel`` secondary chains (``standard``). On the schematic
the chains of a deck share only ideal sources (supplies, clocks, Vref) and the load bias node, so a
deck may hold any chains of one array, each at its own charge and with its own perturbation
(``packed``): every chain of the surrogate's decks is then a measurement of its own, where the
dual-pixel bench simulates a primary measurement beside three identical secondary copies. A packed
deck holds the chains of one array only, so a revision that changes only the other array runs the
same decks (the engine's cache serves them). A post-layout view couples the column lines and
carries the dual pixel's wiring: its chains are not independent, and it keeps the dual-pixel bench
(``packable``).

Each chain of either bench has its own copies of the subcircuits a perturbation edits (the
subpixel, the AFE; on a packed deck also the AFE's op-amp), named in its ``Chain``.

Every gap deck (these benches, the virtual silicon's, the readout-light decks) is integrated with a
largest time step of one clock edge (``edge_resolved``), not the dual-pixel bench's 20 ns: at 20 ns the
simulator's step control can step over the charge sharing that follows an edge (S1X connecting the
column to C11) and settle on another solution. Measured on the reference design, a deck with the primary
at 17 fC and its secondaries at 0.8 / 5.4 / 14 fC left every chain's levels 1.5 - 2.4 mV (the AFE
output up to 8 mV mid-read) from the same deck at an eighth of the step, where ten other mixed decks and
the same deck at one edge stay within 0.2 mV of it (``tests/test_gap_surrogate.py``): the error is rare
but ten times the surrogate's stated error, and the virtual silicon's decks mix charges.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, replace

from ..circuits.testbench import dual_pixel_bench, timings
from ..spice.netlist import Element

#: chains per packed deck (the dual-pixel bench's count: decks of the same size and cost)
PACK = 4


@dataclass(frozen=True)
class Chain:
    array: str          # primary | secondary
    pixel: str          # its subpixel's subcircuit (its own copy)
    col: str            # its column line node (the AFE input is in_<col>, the output out_<col>)
    afe: str            # its AFE's subcircuit (its own copy)
    opamp: str | None   # its own op-amp subcircuit (packed), None when the deck's AFEs share one (standard)
    rs: str             # the row-select line of its array

    @property
    def out(self) -> str:
        return f"out_{self.col}"


def edge_resolved(net, design):
    """``net`` with its largest time step at most one clock edge of the design's read (``GsTiming.edge``,
    the shortest element of the phase timing; see the module docstring)."""
    step = min(t.edge for t in timings(design, design.experiment.t_window).values())
    a = net.analysis
    if a.max_step is not None and a.max_step <= step:
        return net
    return replace(net, analysis=replace(a, max_step=step))


def packable(design) -> bool:
    """Chains of this design's decks are independent (schematic view: nothing couples the column lines)."""
    return getattr(design, "post_layout", None) is None


def standard_chains(design) -> tuple:
    """The chains of ``dual_pixel_bench(with_afe=True)`` after ``circuit_edits.specialise``."""
    n = design.secondary_per_pixel
    return (Chain("primary", "pix5t_primary", "col_p", "scafe_col_p", None, "rs_p"),
            *(Chain("secondary", f"pix5t_s{k}", f"col_s{k}", f"scafe_col_s{k}", None, "rs_s") for k in range(n)))


def standard(design, q_p: float, q_s, title: str):
    """(deck, chains): the dual-pixel bench with its AFEs at charges ``q_p`` and ``q_s`` (C, one per
    secondary), each subpixel and AFE its own subcircuit copy."""
    from .circuit_edits import specialise
    n = design.secondary_per_pixel
    t_w = design.experiment.t_window
    q_s = tuple(q_s) if isinstance(q_s, (tuple, list)) else (q_s,) * n
    net = specialise(dual_pixel_bench(design, q_p / t_w, tuple(q / t_w for q in q_s), with_afe=True, title=title), n)
    return edge_resolved(net, design), standard_chains(design)


def _other_clock(other: str):
    return re.compile(rf"_{other}b?$")


def packed(design, array: str, charges, title: str):
    """(deck, chains): ``len(charges)`` (at most ``PACK``) chains of ``array`` at those charges (C), read as
    the dual-pixel bench reads that array (its clocks, column circuit and AFE), nothing of the other array."""
    if not packable(design):
        raise ValueError("a post-layout view couples its column lines: its chains cannot be packed")
    if not 1 <= len(charges) <= PACK:
        raise ValueError(f"1 .. {PACK} chains per packed deck, not {len(charges)}")
    n = design.secondary_per_pixel
    base = edge_resolved(dual_pixel_bench(design, 0.0, (0.0,) * n, with_afe=True, title=title), design)
    s, other = ("p", "s") if array == "primary" else ("s", "p")
    src = "col_p" if array == "primary" else "col_s0"
    cols = ["col_p", *(f"col_s{k}" for k in range(n))]
    chain_nodes = {x for c in cols for x in (c, f"in_{c}", f"out_{c}")}
    mine = {src, f"in_{src}", f"out_{src}"}
    other_clock = _other_clock(other)
    template = [e for e in base.elements if e.name != "X1" and set(e.nodes) & mine]
    shared = [e for e in base.elements if e.name != "X1" and not set(e.nodes) & chain_nodes
              and not any(other_clock.search(x) for x in e.nodes)]
    subs = {sc.name: sc for sc in base.subckts}
    pix = subs["pix5t_primary" if array == "primary" else "pix5t_secondary"]
    afe, op_name = subs["scafe"], next(e.value for e in subs["scafe"].elements if e.name == "Xop")
    t_w = design.experiment.t_window
    elements, new_subs, chains = list(shared), [sc for sc in base.subckts if sc.name not in
                                                ("dualpix", "pix5t_primary", "pix5t_secondary", "scafe", op_name)], []
    for k, q in enumerate(charges):
        col = f"col_c{k}"
        ren = {src: col, f"in_{src}": f"in_{col}", f"out_{src}": f"out_{col}"}
        elements.append(Element(f"Xpix_c{k}", ("vdd", "vpdr", "vrst", f"ec_{s}", f"tg_{s}", f"rst_{s}", f"rs_{s}",
                                               col), f"pix5t_c{k}", (("iph", q / t_w),)))
        for e in template:
            value = f"scafe_{col}" if e.value == "scafe" else e.value
            elements.append(replace(e, name=e.name.replace(src, col), nodes=tuple(ren.get(x, x) for x in e.nodes),
                                    value=value))
        new_subs += [replace(pix, name=f"pix5t_c{k}"),
                     replace(afe, name=f"scafe_{col}", elements=tuple(
                         replace(e, value=f"opamp_c{k}") if e.name == "Xop" else e for e in afe.elements)),
                     replace(subs[op_name], name=f"opamp_c{k}")]
        chains.append(Chain(array, f"pix5t_c{k}", col, f"scafe_{col}", f"opamp_c{k}", f"rs_{s}"))
    return replace(base, elements=tuple(elements), subckts=tuple(new_subs)), tuple(chains)
