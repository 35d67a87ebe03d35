"""The AFE's op-amp: a behavioural macromodel or a transistor-level two-stage OTA.

Both are subcircuits with ports ``inp inn out vdd``.

Macromodel (``opamp_macro``): a transconductance into R || C (one pole) and an
ideal output buffer: DC gain A = gm R, gain-bandwidth GBW = gm / (2 pi C), an
input offset ``vos`` in series with ``inp``. A Gm-R model runs
faster than the transistor OTA; it has no infinite-bandwidth source (which makes
ngspice's time step collapse at the switch edges).

Its input-referred noise, e_n^2(f) = 4 k T R_n (1 + f_c / f) V^2/Hz, is made of
elements ngspice's ``.noise`` (and nothing else) sees, in series with ``inp``:

- thermal: a resistor R_n (``afe.noise_r``) between the offset source and the Gm
  input; no current flows into a VCCS input, so the resistor only adds its 4 k T R_n;
- 1/f: a side loop, a 1 A DC current through a 1 Ohm resistor whose model has
  ``kf``, ``af = 2`` (ngspice: S_v = KF I^AF R^2 / f = KF / f), copied into the input
  path by a unity VCVS against a noiseless 1 V reference (so the DC and the
  transient are unchanged). KF = 4 k T R_n f_c puts the corner at f_c at the deck
  temperature. The 1 Ohm's own thermal noise (4 k T x 1 Ohm) is 1/R_n of the white
  level and ignored.

OTA (``opamp_ota``): NMOS differential pair with PMOS mirror load, PMOS common-
source second stage, Miller capacitor with a nulling resistor, biased by one
reference current ``afe.ota_bias`` (the mirrors: tail 2x, output stage 4x, so the OTA draws
7x it). Sizes are set for Vref ~ 2 V input common mode at 3.3 V; they do not follow the bias,
so the layout (which brings the reference in on the pin ``nb``) is the same at any bias.
"""
from __future__ import annotations

import math

from ..constants import K_B
from ..spice.netlist import Element, Param, Subckt
from .devices import mosfet

PORTS = ("inp", "inn", "out", "vdd")
GM = 1e-4  # S; only the products gm R and gm / C matter


def flicker_kf(r_noise: float, f_corner: float, temperature_K: float) -> float:
    """KF of the 1 Ohm / 1 A flicker generator: its 1/f PSD equals 4 k T R_n at f_corner."""
    return 4.0 * K_B * temperature_K * r_noise * f_corner


def opamp_macro(gain: float, gbw: float, r_noise: float = 0.0, f_corner: float = 0.0,
                temperature_K: float = 300.15) -> Subckt:
    r = gain / GM
    c = GM / (2 * math.pi * gbw)
    noise, models, node = [], (), "inpo"
    if r_noise > 0:
        noise.append(Element("Rn", ("inpo", "inpn"), r_noise))
        node = "inpn"
        if f_corner > 0:
            kf = flicker_kf(r_noise, f_corner, temperature_K)
            noise += [Element("Ifl", ("0", "nfl"), 1.0), Element("Rfl", ("nfl", "0"), "rflicker", (("r", 1.0),)),
                      Element("Vflr", ("nflr", "0"), 1.0),
                      Element("Efl", ("inpf", node, "nfl", "nflr"), 1.0)]
            models = (("rflicker", "r", (("kf", kf), ("af", 2.0))),)
            node = "inpf"
    return Subckt("opamp_macro", PORTS, (
        Element("Vos", ("inp", "inpo"), Param("vos")),
        *noise,
        Element("Gm", ("0", "n1", node, "inn"), GM),
        Element("R1", ("n1", "0"), r),
        Element("C1", ("n1", "0"), c),
        Element("Eout", ("out", "0", "n1", "0"), 1.0),
    ), (("vos", 0.0),), models)


#: Supply current of the OTA per unit of reference current (reference 1, tail 2, output stage 4).
OTA_MIRROR_SUM = 7.0


def opamp_ota(tech, i_bias: float = 10e-6, cc: float = 1e-12, rz: float = 5e3) -> Subckt:
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
        Element("Rz", ("n2", "nz"), rz),
        Element("Cc", ("nz", "out"), cc),
    ))


def macro(design) -> Subckt:
    """The design's macromodel: its gain, GBW and input noise at the design temperature."""
    a = design.afe
    return opamp_macro(a.gain, a.gbw, a.noise_r, a.noise_corner, design.temperature)


def ota(design) -> Subckt:
    """The design's transistor OTA: its reference current and compensation."""
    a = design.afe
    return opamp_ota(design.tech, a.ota_bias, a.ota_cc, a.ota_rz)


def opamp(design) -> Subckt:
    """The op-amp the design chose."""
    return macro(design) if design.afe.opamp == "macro" else ota(design)
