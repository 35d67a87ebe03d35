"""Edits of a full-chain deck (``dual_pixel_bench(with_afe=True)``) as Netlist data.

Effects are inserted as circuit elements by transforming the Netlist object,
never by editing the shared generators: an element added inside one
subpixel's or one column's AFE subcircuit (each secondary subpixel and each
AFE gets its own copy of its subcircuit first, so columns can differ), a
parameter of a top-level element changed, a diode model added.

The hold window of the FD (from the end of the global transfer to the first
row's read) is where storage-node currents act; ``hold_window`` gives it and
``pulse_charge`` the charge a PWL pulse of that window delivers.
"""
from __future__ import annotations

from dataclasses import replace

from ..circuits.testbench import timings
from ..spice.netlist import Element, Model, Netlist, Pwl, Subckt

COLS = ("col_p", "col_s0", "col_s1", "col_s2")
EDGE = 10e-9


def specialise(net: Netlist, n_secondary: int) -> Netlist:
    """Give every secondary subpixel and every column's AFE its own subcircuit copy."""
    subs = {s.name: s for s in net.subckts}
    new = [s for s in net.subckts if s.name not in ("dualpix", "scafe")]
    for k in range(n_secondary):
        new.append(replace(subs["pix5t_secondary"], name=f"pix5t_s{k}"))
    dp = subs["dualpix"]
    els = tuple(replace(e, value=f"pix5t_s{e.name[2:]}") if e.name.startswith("Xs") else e for e in dp.elements)
    new.append(replace(dp, elements=els))
    cols = [e.name[5:] for e in net.elements if e.name.startswith("Xafe_")]
    if "scafe" in subs:
        for c in cols:
            new.append(replace(subs["scafe"], name=f"scafe_{c}"))
    els = tuple(replace(e, value=f"scafe_{e.name[5:]}") if e.name.startswith("Xafe_") else e for e in net.elements)
    return replace(net, subckts=tuple(new), elements=els)


def pixel_subckt(which: str) -> str:
    """``primary`` or ``s0``, ``s1``...: the subcircuit name of that subpixel after ``specialise``."""
    return "pix5t_primary" if which == "primary" else f"pix5t_{which}"


def add_to_subckt(net: Netlist, name: str, *elements: Element) -> Netlist:
    subs = tuple(replace(s, elements=s.elements + tuple(elements)) if s.name == name else s for s in net.subckts)
    if subs == net.subckts:
        raise KeyError(name)
    return replace(net, subckts=subs)


def add_top(net: Netlist, *elements: Element, models: tuple = ()) -> Netlist:
    return replace(net, elements=net.elements + tuple(elements), models=net.models + tuple(models))


def set_param(net: Netlist, suffix: str, key: str, fn) -> Netlist:
    """Change parameter ``key`` of the top-level element whose name ends with ``suffix``."""
    els = []
    for e in net.elements:
        if e.name.endswith(suffix):
            e = replace(e, params=tuple((k, fn(v) if k == key else v) for k, v in e.params))
        els.append(e)
    return replace(net, elements=tuple(els))


def scale_in_subckt(net: Netlist, name: str, element: str, key: str, factor: float) -> Netlist:
    """Parameter ``key`` of ``element`` inside subcircuit ``name`` times ``factor`` (a device's W)."""
    subs = tuple(replace(s, elements=tuple(replace(e, params=tuple((k, v * factor if k == key else v)
                                                                   for k, v in e.params)) if e.name == element else e
                                           for e in s.elements)) if s.name == name else s for s in net.subckts)
    return replace(net, subckts=subs)


def scale_value_in_subckt(net: Netlist, name: str, element: str, factor: float) -> Netlist:
    """The value of ``element`` inside subcircuit ``name`` times ``factor`` (unchanged if there is none)."""
    subs = tuple(replace(s, elements=tuple(replace(e, value=e.value * factor) if e.name == element else e
                                           for e in s.elements)) if s.name == name else s for s in net.subckts)
    return replace(net, subckts=subs)


def scale_caps(net: Netlist, afe: str, factors: dict) -> Netlist:
    """Scale capacitors (by element name) of one AFE copy (numbers, or the subcircuit's parameter defaults)."""
    from ..spice.netlist import Param
    subs = []
    for s in net.subckts:
        if s.name == afe:
            for name, factor in factors.items():
                c = next(e for e in s.elements if e.name == name)
                if isinstance(c.value, Param):
                    s = replace(s, params=tuple((k, v * factor if k == c.value.name else v) for k, v in s.params))
                else:
                    s = replace(s, elements=tuple(replace(e, value=e.value * factor) if e.name == name else e
                                                  for e in s.elements))
        subs.append(s)
    return replace(net, subckts=tuple(subs))


def hold_window(design, array: str) -> tuple[float, float]:
    """(start, end) of the FD hold before the first row's signal sample, in deck time."""
    t = timings(design, design.experiment.t_window)[array]
    return t.t_tx + 2 * EDGE, t.t_read


def pulse(t0: float, t1: float, value: float) -> Pwl:
    return Pwl(((0.0, 0.0), (t0, 0.0), (t0 + EDGE, value), (t1 - EDGE, value), (t1, 0.0)))


def pulse_charge(t0: float, t1: float, value: float) -> float:
    """Charge of ``pulse(t0, t1, value)`` (trapezoid)."""
    return value * (t1 - t0 - EDGE)


def fd_current(design, array: str, charge: float, which: str, tag: str) -> Element:
    """A current source on FD during the hold that delivers ``charge`` (C; + lowers the FD)."""
    t0, t1 = hold_window(design, array)
    return Element(f"I{tag}", ("fd", "0"), pulse(t0, t1, charge / (t1 - t0 - EDGE)))


def vm_current(design, array: str, value: float) -> Element:
    """A current ``value`` (A; + draws charge out of the node) on an AFE's virtual-ground node ``vm``,
    flowing from the start of the row to the end of the deck (the AFE is clocked only during its row)."""
    t = timings(design, design.experiment.t_window)[array]
    return Element("Ilt", ("vm", "0"), pulse(t.row(0), t.t_stop - EDGE, value))


DIODE = Model("dfault", "d", (("is", 1e-15), ("n", 1.0)))


def column_conductance(net: Netlist, design, col: str, v_pivot: float, g: float, tag: str = "sf",
                       gate: str | None = None) -> Netlist:
    """A conductance ``g`` (S) from column line ``col`` to a source at ``v_pivot``, switched in with the
    row select ``gate`` of the column's array (default: the dual-pixel bench's, by the column's name;
    connected while a row is read): a load on the column."""
    from ..circuits.devices import mosfet
    gate = gate or ("rs_p" if col == "col_p" else "rs_s")
    return add_top(net, Element(f"Vpiv_{col}", (f"piv_{col}", "0"), v_pivot),
                   mosfet(f"sw_{col}", col, gate, f"m_{col}", "0", 1e-6, 0.35e-6, design.tech),
                   Element(f"R{tag}_{col}", (f"m_{col}", f"piv_{col}"), 1.0 / g))


def offset_gate(net: Netlist, suffix: str, dv: float) -> Netlist:
    """The top-level MOSFET whose name ends with ``suffix`` with its threshold raised by ``dv`` (V): its gate
    driven through a source of -dv from the node it was on (the threshold mismatch of one device)."""
    els, added = [], []
    for e in net.elements:
        if e.name.endswith(suffix):
            g = f"g_{e.name}"
            added.append(Element(f"Vdvt_{e.name}", (g, e.nodes[1]), -dv))
            e = replace(e, nodes=(e.nodes[0], g, *e.nodes[2:]))
        els.append(e)
    return replace(net, elements=tuple(els + added))


def scale_load(net: Netlist, col: str, factor: float) -> Netlist:
    """The column load of ``col`` with its width (so its current) times ``factor``."""
    return set_param(net, f"ld_{col}", "w", lambda v: v * factor)


def afe_coupling(c: float, tag: str = "Ccp") -> Element:
    """A coupling capacitor |c| onto an AFE's virtual ground vm from its p1 clock (c > 0) or from the
    complement p1b (c < 0): a clock kick of either sign at every p1 edge."""
    return Element(tag, ("p1" if c > 0 else "p1b", "vm"), abs(c))
