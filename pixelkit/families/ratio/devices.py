"""What the kit's loop device does in weak inversion (one operating-point deck).

Two measurements on the loop NMOS (the design's W/L, bulk at ground):

- subthreshold slope: diode-connected devices fed 1, 2, 20, 40, 100 and 200 nA;
  n U_T = (V_GS(2 I) - V_GS(I)) / ln 2 at 1, 20 and 100 nA. A pure weak-inversion
  device has n U_T constant; it grows as the device enters moderate inversion.
- source shift: at a fixed gate, moving the source from v_source to v_source - 0.1 V
  multiplies the current by exp(0.1 / U_T) in the bulk-referenced law the loop's
  derivation uses (``law.py``); measured at two gate levels (a low and a higher current).
"""
from __future__ import annotations

import math

from ...circuits.devices import mosfet
from ...constants import K_B, Q
from ...spice import simulate
from ...spice.netlist import Element, Netlist, Op

CURRENTS = (1e-9, 2e-9, 20e-9, 40e-9, 100e-9, 200e-9)
SHIFT = 0.1
GATE_OVER_SOURCE = (0.4, 0.5)   # gate above v_source: ~tens of pA and ~0.3 nA (W/L = 4/1)


def deck(design, v_gates) -> Netlist:
    t, lp = design.tech, design.loop
    el = [Element("Vdd", ("vdd", "0"), t.supply),
          Element("Vs0", ("s0", "0"), lp.v_source), Element("Vs1", ("s1", "0"), lp.v_source - SHIFT)]
    for k, i in enumerate(CURRENTS):
        el += [Element(f"I{k}", ("vdd", f"g{k}"), i), mosfet(f"d{k}", f"g{k}", f"g{k}", "0", "0", lp.w, lp.l, t)]
    for k, vg in enumerate(v_gates):
        el += [Element(f"Vg{k}", (f"vg{k}", "0"), vg),
               Element(f"Va{k}", ("vdd", f"da{k}"), 0.0), Element(f"Vb{k}", ("vdd", f"db{k}"), 0.0),
               mosfet(f"a{k}", f"da{k}", f"vg{k}", "s0", "0", lp.w, lp.l, t),
               mosfet(f"b{k}", f"db{k}", f"vg{k}", "s1", "0", lp.w, lp.l, t)]
    return Netlist(title="ratio_loop_device", elements=tuple(el), analysis=Op(),
                   includes=t.models.includes(design.corner or None), temperature_C=design.temperature - 273.15)


def weak_inversion(design, backend: str = "batch") -> dict:
    """n U_T vs current, and the source-shift current ratio against exp(0.1 / U_T)."""
    u_t = K_B * design.temperature / Q
    v_gates = [design.loop.v_source + dv for dv in GATE_OVER_SOURCE]
    r = simulate(deck(design, v_gates), backend=backend)
    vgs = [float(r.v(f"g{k}")[0]) for k in range(len(CURRENTS))]
    n_ut = {f"{CURRENTS[k] * 1e9:g}nA": (vgs[k + 1] - vgs[k]) / math.log(2) for k in (0, 2, 4)}
    shift = []
    for k, vg in enumerate(v_gates):
        ia, ib = abs(float(r[f"i(va{k})"][0])), abs(float(r[f"i(vb{k})"][0]))
        shift.append({"v_gate_V": vg, "i_A": ia, "ratio": ib / ia})
    return {"n_ut_V": n_ut, "source_shift_V": SHIFT, "ideal_ratio": math.exp(SHIFT / u_t), "shift": shift}
