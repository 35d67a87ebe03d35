"""The WDR pixel (paper fig. 2) as netlist data, and its bench.

Per pixel (subcircuit ``wdr_pixel``)::

    PD (n-well/p-sub, the technology's junction) + photocurrent on node pd
    Mrst   vrst -> int, gate rst         reset; its low level v_ab makes the
    Mab    vrst -> pd,  gate rst         ... PD clamp (anti-blooming) after a flip
    Men    pd -> mid, gate en            integration switch: opens at the flip
    Mexp   mid -> int, gate expo         global end of the fixed exposure 2^N T
    C_int  int -> 0                      integration capacitor
    comparator (transistor level): NMOS pair (int, v0), PMOS mirror, NMOS tail
      from the column bias vbn; output cmp is high while V(int) > V0
    inverters: cmp -> flip -> en (en low after the flip)
    delay: flip -> R -> dly (C_d) -> two inverters -> samp (the delayed
      sampling pulse: high = hold)
    PMOS read-in switches (gate samp, n-well at v_high): sig1 -> c1, sig2 -> c2
    C1, C2 storage capacitors

Low light: the comparator never flips, the exposure ends at 2^N T when expo
falls; V(int) is signal 3. High light: V(int) reaches V0 at t_c, the integration
switch opens (V(int) stays near V0), and t_d later the read-in switches open:
C1 and C2 hold signal1 and signal2 at t_c + t_d.

The comparator is transistor level (not behavioural) because its delay and its
input-referred offset are exactly the "analog delay" the paper blames for its
distorted high-light range; a behavioural switch would hide them. C_int, C1, C2
and the delay R are ideal elements: the open GF180 wheel ships no MIM-capacitor
model.
"""
from __future__ import annotations

import math

from ...circuits.devices import mosfet, photodiode, photodiode_model
from ...spice.netlist import Element, Netlist, Param, Pwl, Subckt, Tran
from .stimulus import signal1, signal2

PORTS = ("vdd", "vrst", "v0", "vbn", "vwell", "rst", "expo", "sig1", "sig2", "int", "c1", "c2")
T_RESET = 2e-6
EDGE = 10e-9
#: gmin of the bench: ngspice's default 1e-15 S across every junction would leak 7e-15 A from the node at 2 V,
#: 20 x the node's dark current (physics.dark); 1e-18 S leaks < 1 % of it
GMIN = 1e-18


def _inverter(name, a, y, t):
    return (mosfet(f"{name}p", y, a, "vdd", "vdd", 1e-6, 0.5e-6, t, "p"),
            mosfet(f"{name}n", y, a, "0", "0", 0.5e-6, 0.5e-6, t, "n"))


def wdr_pixel(design) -> Subckt:
    t, px, cp, cd = design.tech, design.pixel, design.comparator, design.coding
    r_delay = cd.t_delay / (cd.delay_c * math.log(2.0))
    return Subckt("wdr_pixel", PORTS, (
        photodiode("pd", "pd", px.area, px.perimeter, t),
        Element("Iph", ("pd", "0"), Param("iph")),
        mosfet("rst", "vrst", "rst", "int", "0", px.sw_w, px.sw_l, t),
        mosfet("ab", "vrst", "rst", "pd", "0", px.sw_w, px.sw_l, t),
        mosfet("en", "pd", "en", "mid", "0", px.sw_w, px.sw_l, t),
        mosfet("exp", "mid", "expo", "int", "0", px.sw_w, px.sw_l, t),
        Element("Cint", ("int", "0"), px.c_int),
        mosfet("c1", "a", "int", "tail", "0", cp.in_w, cp.in_l, t),
        mosfet("c2", "cmp", "v0", "tail", "0", cp.in_w, cp.in_l, t),
        mosfet("c3", "a", "a", "vdd", "vdd", cp.load_w, cp.load_l, t, "p"),
        mosfet("c4", "cmp", "a", "vdd", "vdd", cp.load_w, cp.load_l, t, "p"),
        mosfet("ct", "tail", "vbn", "0", "0", cp.tail_w, cp.tail_l, t),
        *_inverter("i1", "cmp", "flip", t),
        *_inverter("i2", "flip", "en", t),
        Element("Rd", ("flip", "dly"), r_delay),
        Element("Cd", ("dly", "0"), cd.delay_c),
        *_inverter("i3", "dly", "dlyb", t),
        *_inverter("i4", "dlyb", "samp", t),
        mosfet("s1", "c1", "samp", "sig1", "vwell", cd.sw_w, cd.sw_l, t, "p"),
        mosfet("s2", "c2", "samp", "sig2", "vwell", cd.sw_w, cd.sw_l, t, "p"),
        Element("C1", ("c1", "0"), cd.c_store),
        Element("C2", ("c2", "0"), cd.c_store),
    ), (("iph", 0.0),))


def t_exposure(design) -> float:
    return (2 ** design.coding.steps) * design.coding.t_unit


def wdr_bench(design, currents, title: str = "wdr_bench") -> Netlist:
    """One pixel per photocurrent, sharing the coding buses, bias and controls.

    0 .. T_RESET: reset (rst high); exposure from T_RESET for 2^N T (expo high);
    the frame is read at the end (the storage nodes and V(int) hold).
    """
    t, px, cd = design.tech, design.pixel, design.coding
    vdd = t.supply
    t0 = T_RESET
    t_end = t0 + t_exposure(design)
    stop = t_end + 20e-6
    el = [Element("Vdd", ("vdd", "0"), vdd), Element("Vrst", ("vrst", "0"), px.v_reset),
          Element("Vv0", ("v0", "0"), px.v0), Element("Vwell", ("vwell", "0"), cd.v_high),
          Element("Vrstg", ("rst", "0"), Pwl(((0.0, vdd), (t0 - EDGE, vdd), (t0, px.v_ab)))),
          Element("Vexpo", ("expo", "0"), Pwl(((0.0, vdd), (t_end, vdd), (t_end + EDGE, 0.0)))),
          Element("Vsig1", ("sig1", "0"), signal1(cd, t0, stop)),
          Element("Vsig2", ("sig2", "0"), signal2(cd, t0, stop)),
          Element("Ibias", ("vdd", "vbn"), design.comparator.i_tail),
          mosfet("bias", "vbn", "vbn", "0", "0", design.comparator.tail_w, design.comparator.tail_l, t)]
    for k, i in enumerate(currents):
        el.append(Element(f"Xp{k}", ("vdd", "vrst", "v0", "vbn", "vwell", "rst", "expo", "sig1", "sig2",
                                     f"out_s3_{k}", f"out_s1_{k}", f"out_s2_{k}"), "wdr_pixel",
                          (("iph", float(i)),)))
    saves = [f"out_{n}_{k}" for k in range(len(currents)) for n in ("s3", "s1", "s2")]
    saves += [f"xp{k}.{n}" for k in range(len(currents)) for n in ("samp", "pd")] + ["sig1", "sig2"]
    return Netlist(title=title, elements=tuple(el), analysis=Tran(100e-9, stop, 0.0, cd.t_unit / 16),
                   subckts=(wdr_pixel(design),), models=photodiode_model(t, design.temperature),
                   includes=t.models.includes(design.corner or None),
                   temperature_C=design.temperature - 273.15, saves=tuple(saves), options=(("gmin", GMIN),))
