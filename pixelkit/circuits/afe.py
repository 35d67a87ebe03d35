"""Switched-capacitor double-sampling AFE ([Thesis2019] fig. 3.3, eq. 3.1).

Offset-compensated gain stage with input offset storage; ports
``in out vref p1 p1b p2 p2b vdd``:

    C11: in -> vm        input capacitor
    C12: vm -> x         offset storage (op-amp inverting input at x)
    C13: vm -> c         feedback capacitor
    phase 1 (p1): x <-> out (unity feedback), vm <-> vref, c <-> vref
    phase 2 (p2): c <-> out (C13 closes the loop)

In phase 1 C12 stores the op-amp offset and C11 the signal level Vsig; in
phase 2 the input moves to the reset level Vrst and the charge C11 (Vrst - Vsig)
lands on C13: Vout = Vref - (C11/C13)(Vrst - Vsig), the offset cancelled.

With finite gain A, charge conservation at vm gives (derivation in
``measure.afe.finite_gain_output``):

    Vout = Vref - (C11/C13) (Vrst - Vsig) / (1 + eps),  eps = (C11 + C13 + Cp) / (A C13)

plus a residual offset ~ eps Vos; Cp is the parasitic capacitance at vm.
"""
from __future__ import annotations

from ..spice.netlist import Element, Param, Subckt
from .devices import tgate
from .pixel5t import wiring

PORTS = ("in", "out", "vref", "p1", "p1b", "p2", "p2b", "vdd")
SWITCH_W, SWITCH_L = 1e-6, 0.35e-6


def sc_afe(design) -> Subckt:
    """The AFE cell; its capacitors are parameters (default: the design's values), so a
    Monte Carlo instance can carry its own drawn values (``Xafe ... c11=...``)."""
    a, t = design.afe, design.tech
    op = "opamp_macro" if a.opamp == "macro" else "opamp_ota"
    return Subckt("scafe", PORTS, (
        Element("C11", ("in", "vm"), Param("c11")),
        Element("C12", ("vm", "x"), Param("c12")),
        Element("C13", ("vm", "c"), Param("c13")),
        *tgate("Sfb", "x", "out", "p1", "p1b", SWITCH_W, SWITCH_L, t),
        *tgate("Sref", "vm", "vref", "p1", "p1b", SWITCH_W, SWITCH_L, t),
        *tgate("Sc", "c", "vref", "p1", "p1b", SWITCH_W, SWITCH_L, t),
        *tgate("So", "c", "out", "p2", "p2b", SWITCH_W, SWITCH_L, t),
        Element("Xop", ("vref", "x", "out", "vdd"), op),
        *wiring(design, "scafe"),
    ), (("c11", a.c11), ("c12", a.c12), ("c13", a.c13)))
