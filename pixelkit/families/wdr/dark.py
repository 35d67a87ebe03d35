"""Dark current of the WDR pixel's integration node as a function of its voltage.

The node (C_int + PD + switches, integration switches closed) is held at each
voltage by a source and the current it sinks is read after 15 us: the PD
junction's and the switch diffusions' reverse currents at that bias (the
decoder models I_dark(V) rather than one dark rate; with GF180's foundry
card the tunnelling term made it fall with the bias, ``techfit.pdcard``).
"""
from __future__ import annotations

from dataclasses import replace

from ...spice import simulate
from ...spice.netlist import Element, Tran
from .circuit import wdr_bench

VOLTAGES = (2.0, 1.9, 1.8, 1.6, 1.4, 1.25)
T_READ = 15e-6


def dark_current_vs_voltage(design, backend: str = "batch") -> list[dict]:
    net = wdr_bench(design, [0.0] * len(VOLTAGES), title="wdr_dark_vs_v")
    forced = tuple(Element(f"Vf{k}", (f"out_s3_{k}", "0"), v) for k, v in enumerate(VOLTAGES))
    net = replace(net, elements=net.elements + forced, analysis=Tran(1e-6, 20e-6, 0.0, 1e-6), saves=())
    r = simulate(net, backend=backend)
    return [{"v_V": v, "i_dark_A": abs(float(r.at(f"i(vf{k})", T_READ)))} for k, v in enumerate(VOLTAGES)]
