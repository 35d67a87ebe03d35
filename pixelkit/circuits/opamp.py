"""The AFE's op-amp: a behavioural macromodel or a transistor-level two-stage OTA.

Both are subcircuits with ports ``inp inn out vdd``.

Macromodel (``opamp_macro``): a transconductance into R || C (one pole) and an
ideal output buffer: DC gain A = gm R, gain-bandwidth GBW = gm / (2 pi C), an
input offset ``vos`` in series with ``inp``. NGSPICE_NOTES: a Gm-R model runs
faster than the OTA; avoid infinite-bandwidth sources.

OTA (``opamp_ota``): NMOS differential pair with PMOS mirror load, PMOS common-
source second stage, Miller capacitor with a nulling resistor, biased by one
reference current. Sizes are set for Vref ~ 2 V input common mode at 3.3 V.
"""
from __future__ import annotations

import math

from ..spice.netlist import Element, Param, Subckt
from .devices import mosfet

PORTS = ("inp", "inn", "out", "vdd")
GM = 1e-4  # S; only the products gm R and gm / C matter


def opamp_macro(gain: float, gbw: float) -> Subckt:
    r = gain / GM
    c = GM / (2 * math.pi * gbw)
    return Subckt("opamp_macro", PORTS, (
        Element("Vos", ("inp", "inpo"), Param("vos")),
        Element("Gm", ("0", "n1", "inpo", "inn"), GM),
        Element("R1", ("n1", "0"), r),
        Element("C1", ("n1", "0"), c),
        Element("Eout", ("out", "0", "n1", "0"), 1.0),
    ), (("vos", 0.0),))


def opamp_ota(tech, i_bias: float = 10e-6) -> Subckt:
    u = 1e-6
    return Subckt("opamp_ota", PORTS, (
        Element("Ib", ("vdd", "nb"), i_bias),
        mosfet("b", "nb", "nb", "0", "0", 4 * u, 1 * u, tech),
        mosfet("1", "n1", "inn", "tail", "0", 8 * u, 1 * u, tech),
        mosfet("2", "n2", "inp", "tail", "0", 8 * u, 1 * u, tech),
        mosfet("3", "n1", "n1", "vdd", "vdd", 4 * u, 1 * u, tech, "p"),
        mosfet("4", "n2", "n1", "vdd", "vdd", 4 * u, 1 * u, tech, "p"),
        mosfet("5", "tail", "nb", "0", "0", 8 * u, 1 * u, tech),
        mosfet("6", "out", "n2", "vdd", "vdd", 32 * u, 0.5 * u, tech, "p"),
        mosfet("7", "out", "nb", "0", "0", 16 * u, 1 * u, tech),
        Element("Rz", ("n2", "nz"), 5e3),
        Element("Cc", ("nz", "out"), 1e-12),
    ))


def opamp(design) -> Subckt:
    """The op-amp the design chose."""
    a = design.afe
    return opamp_macro(a.gain, a.gbw) if a.opamp == "macro" else opamp_ota(design.tech)
