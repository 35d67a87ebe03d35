"""The ratio pixel as netlist data (paper fig. 2), its column readout and its bench.

One translinear loop per photodiode pair (``ratio_loop``)::

    PD+ (p+/n-well, n-well at VDD) -> g3, M3 diode-connected (g3, source vsrc)
    PD- -> g4, M4 diode-connected (g4, source vsrc)
    M1: drain d1, gate g4, source s     I_out+ (grows with I_PD-)
    M2: drain d2, gate g3, source s     I_out- (grows with I_PD+)
    Mt: tail NMOS s -> 0, gate vbn      I_out+ + I_out- = I_bias
    Ms1, Ms2: row select d1 -> out_p, d2 -> out_m

M3/M4 share their source and M1/M2 share theirs, so the bulk-referenced
weak-inversion law I = I0 exp((kappa V_G - V_S)/U_T) closes the loop without a
body-effect exponent: I_out+/I_out- = I_PD-/I_PD+ (derivation in ``law.py``).
The photocurrent has to flow *into* the diode-connected NMOS, hence the p+/n-well
photodiode (the n-well/p-substrate one would pull current out of the node).
``vsrc`` lifts the M3/M4 sources so the tail keeps its headroom:
V_S = v_source + U_T ln(I_PD/I_out).

A pixel (``ratio_pixel``) holds two loops: horizontal (h) and vertical (v)
pairs. Each column line has a precharge PMOS (gate ``preb``), its parasitic
capacitance C_par and an inverter whose output goes to the behavioural counter
(``counter.py``). The bias comes from a column mirror (``vbn``).
"""
from __future__ import annotations

from ...circuits.devices import mosfet, photodiode_model
from ...spice.netlist import Element, Netlist, Param, Pwl, Subckt, Tran

LOOP_PORTS = ("vdd", "vsrc", "vbn", "sel", "out_p", "out_m")
PIXEL_PORTS = ("vdd", "vsrc", "vbn", "sel", "h_p", "h_m", "v_p", "v_m")
T_PRE = 2e-6        # precharge (loop settled from the operating point) before release
EDGE = 10e-9


def ratio_loop(design) -> Subckt:
    t, lp, pd = design.tech, design.loop, design.photodiodes
    return Subckt("ratio_loop", LOOP_PORTS, (
        Element("Dp", ("g3", "vdd"), pd.pd_model, (("area", pd.area), ("pj", pd.perimeter))),
        Element("Dm", ("g4", "vdd"), pd.pd_model, (("area", pd.area), ("pj", pd.perimeter))),
        Element("Ip", ("vdd", "g3"), Param("ipd_p")),
        Element("Im", ("vdd", "g4"), Param("ipd_m")),
        mosfet("m3", "g3", "g3", "vsrc", "0", lp.w, lp.l, t),
        mosfet("m4", "g4", "g4", "vsrc", "0", lp.w, lp.l, t),
        mosfet("m1", "d1", "g4", "s", "0", lp.w, lp.l, t),
        mosfet("m2", "d2", "g3", "s", "0", lp.w, lp.l, t),
        mosfet("mt", "s", "vbn", "0", "0", lp.tail_w, lp.tail_l, t),
        mosfet("ms1", "out_p", "sel", "d1", "0", lp.sel_w, lp.sel_l, t),
        mosfet("ms2", "out_m", "sel", "d2", "0", lp.sel_w, lp.sel_l, t),
    ), (("ipd_p", 0.0), ("ipd_m", 0.0)))


def ratio_pixel() -> Subckt:
    """Horizontal and vertical loops of one pixel."""
    return Subckt("ratio_pixel", PIXEL_PORTS, (
        Element("Xh", ("vdd", "vsrc", "vbn", "sel", "h_p", "h_m"), "ratio_loop",
                (("ipd_p", Param("ih_p")), ("ipd_m", Param("ih_m")))),
        Element("Xv", ("vdd", "vsrc", "vbn", "sel", "v_p", "v_m"), "ratio_loop",
                (("ipd_p", Param("iv_p")), ("ipd_m", Param("iv_m")))),
    ), (("ih_p", 0.0), ("ih_m", 0.0), ("iv_p", 0.0), ("iv_m", 0.0)))


def column_readout(design) -> Subckt:
    """One column line: ammeter from the pixel, precharge PMOS, clamp, C_par, inverter.

    The clamp (an NMOS follower from VDD, gate ``vclamp``) catches the column
    below the inverter's trip point. Without it the column that trips first keeps
    falling until its output transistor leaves saturation, and the tail then
    steers the whole bias into the other side: the second interval shrinks and
    T_c-r no longer follows the law (the law needs both currents constant until
    the second trip).
    """
    t, r = design.tech, design.readout
    return Subckt("ratio_column", ("vdd", "preb", "vclamp", "pix", "col", "out"), (
        Element("Va", ("col", "pix"), 0.0),
        mosfet("pre", "col", "preb", "vdd", "vdd", r.pre_w, r.pre_l, t, "p"),
        mosfet("clamp", "vdd", "vclamp", "col", "0", r.clamp_w, r.clamp_l, t),
        Element("Cpar", ("col", "0"), r.c_par),
        mosfet("ip", "out", "col", "vdd", "vdd", r.inv_wp, r.inv_l, t, "p"),
        mosfet("in", "out", "col", "0", "0", r.inv_wn, r.inv_l, t, "n"),
    ))


def tau_nominal(design, i_bias: float) -> float:
    """tau = C_par (V_dd - V_th) / I_bias with the inverter trip at V_dd / 2 (estimate only)."""
    return design.readout.c_par * design.tech.supply / 2 / i_bias


def ratio_bench(design, pairs, i_bias: float, title: str = "ratio_bench") -> Netlist:
    """Pixels with ``pairs[k] = ((ih_p, ih_m), (iv_p, iv_m))`` read out together.

    Until ``T_PRE`` the columns are precharged (the loop currents flow from VDD
    through the precharge PMOS: their ratio is the loop's DC transfer); then the
    precharge opens and I_out+ and I_out- discharge C_par+ and C_par-.
    """
    vdd = design.tech.supply
    r_max = max(max(a / b, b / a) for pair in pairs for a, b in pair)
    # the slower column trips at (1 + R_F) tau; the node carries more than C_par
    # (inverter gate, junctions: 1.5x on the reference design), so allow 3x
    stop = T_PRE + 3.0 * (1 + r_max) * tau_nominal(design, i_bias)
    lp = design.loop
    el = [Element("Vdd", ("vdd", "0"), vdd), Element("Vsrc", ("vsrc", "0"), lp.v_source),
          Element("Vsel", ("sel", "0"), design.readout.v_select),
          Element("Vclamp", ("vclamp", "0"), design.readout.v_clamp_gate),
          Element("Vpre", ("preb", "0"), Pwl(((0.0, 0.0), (T_PRE, 0.0), (T_PRE + EDGE, vdd)))),
          Element("Ibias", ("vdd", "vbn"), i_bias),
          mosfet("bias", "vbn", "vbn", "0", "0", lp.tail_w, lp.tail_l, design.tech)]
    for k, ((hp, hm), (vp, vm)) in enumerate(pairs):
        el.append(Element(f"Xp{k}", ("vdd", "vsrc", "vbn", "sel", f"h_p{k}", f"h_m{k}", f"v_p{k}", f"v_m{k}"),
                          "ratio_pixel", (("ih_p", hp), ("ih_m", hm), ("iv_p", vp), ("iv_m", vm))))
        for c in ("h_p", "h_m", "v_p", "v_m"):
            el.append(Element(f"Xc_{c}{k}", ("vdd", "preb", "vclamp", f"{c}{k}", f"col_{c}{k}", f"out_{c}{k}"),
                              "ratio_column"))
    t = design.tech
    return Netlist(title=title, elements=tuple(el), analysis=Tran(EDGE, stop, 0.0, stop / 2000),
                   subckts=(ratio_loop(design), ratio_pixel(), column_readout(design)),
                   models=photodiode_model(t, design.temperature), includes=t.models.includes(design.corner or None),
                   temperature_C=design.temperature - 273.15)
