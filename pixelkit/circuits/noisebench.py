"""Decks for ngspice ``.noise``: the pixel in each configuration where noise is sampled.

``.noise`` linearises the circuit at its operating point and integrates the output
noise over frequency; with a switch closed on a node that is then sampled (the
switch opens), the integral is the variance the node keeps (sampled-noise theory).
The BSIM4 channel thermal and flicker noise of the real devices are the sources.

- ``capacitor_deck``: a resistor charging a bare capacitor (kT/C, any R).
- ``fd_sample_deck``: FD as a switch leaves it when it opens - every switch off (so
  the capacitances are those of the open switches, the SF gate with its Miller
  bootstrap at the read operating point) and a resistor standing for the opening
  switch: RST (the NCDS reset sample), or TG between PD and FD plus the resets that
  set the common mode (the signal sample). Sampled with the switch fully on
  instead, the node would include the switch's channel (2.6 fF against 2.0 fF
  for FD in the reference design), which leaves the node when the switch opens.
- ``read_deck``: the SF, RS and column load with FD held by a source: the spectrum
  at the column, which the NCDS difference then weights by 2 (1 - cos 2 pi f dt).
- ``flicker_deck``: one NMOS as a source follower on an ideal current sink; the
  input-referred spectrum (``inoise``) is its gate-referred noise S_vg (1/f at low f).
"""
from __future__ import annotations

from dataclasses import dataclass

from ..spice.netlist import Element, Netlist, check_node, fmt
from .devices import mosfet, photodiode
from .testbench import _deck, read_chain

#: Options of noise decks: floating nodes must not see gmin's 1e-15 S.
NOISE_OPTIONS = (("gmin", 1e-18),)
#: Stand-ins for a switch at the instant it opens (ohm): any resistance leaves kT/C
#: on the node (sampled-noise theory); these only set where the spectrum lies.
R_COMMON = 1e12
R_SWITCH = 1e9


@dataclass(frozen=True)
class Noise:
    """``.noise v(out) Vnoise dec points fstart fstop`` with its input source.

    ``.noise`` needs an input source with an AC value; the analysis writes it
    (``Vnoise pos 0 dc <dc> ac 1``) so a deck's elements stay plain.
    """
    out: str
    pos: str
    dc: float
    f_start: float
    f_stop: float
    points: int = 20

    def text(self) -> str:
        return (f"Vnoise {check_node(self.pos)} 0 dc {fmt(self.dc)} ac 1\n"
                f".noise v({check_node(self.out)}) Vnoise dec {int(self.points)} "
                f"{fmt(self.f_start)} {fmt(self.f_stop)}")

    @property
    def kind(self) -> str:
        return "noise"


def capacitor_deck(design, r: float, c: float) -> Netlist:
    el = (Element("R1", ("in", "out"), r), Element("C1", ("out", "0"), c))
    return _deck(design, "ktc_capacitor", el, (), Noise("out", "in", 0.0, 1e-3 / (r * c), 1e3 / (r * c)))


def _pixel(design, which: str, ec: float, tg: float, rst: float) -> list:
    """One subpixel's PD, switches (gates at fixed levels) and its read chain."""
    sub, dev, t = getattr(design, which), design.pixel.devices, design.tech
    return [*read_chain(design), Element("Vec", ("ec", "0"), ec), Element("Vtg", ("tg", "0"), tg),
            Element("Vrst", ("rst", "0"), rst),
            mosfet("ec", "vpdr", "ec", "pd", "0", dev.ec_w, dev.ec_l, t),
            mosfet("tg", "fd", "tg", "pd", "0", dev.tg_w, dev.tg_l, t),
            mosfet("rst", "vrst", "rst", "fd", "0", dev.rst_w, dev.rst_l, t),
            photodiode("pd", "pd", sub.area, sub.perimeter, t)]


def fd_sample_deck(design, which: str, transfer: bool) -> Netlist:
    """FD as the switch that sets it leaves it: all switches open, a resistor stands for the switch.

    ``transfer=False``: the NCDS reset sample (RST: FD to the reset level).
    ``transfer=True``: the signal sample (TG: PD to FD, and the resets that set the
    common mode: PD to its reset level).
    """
    el = _pixel(design, which, ec=0.0, tg=0.0, rst=0.0)
    if transfer:
        el += [Element("Rtg", ("pd", "fd"), R_SWITCH), Element("Rcm", ("pd", "vpdr"), R_COMMON),
               Element("Vrstd", ("vrst", "0"), design.pixel.v_fd_reset)]
        src, dc = "vpdr", design.pixel.v_pd_reset
    else:
        el += [Element("Rrst", ("fd", "vrst"), R_COMMON), Element("Vpdr", ("vpdr", "0"), design.pixel.v_pd_reset)]
        src, dc = "vrst", design.pixel.v_fd_reset
    kind = "transfer" if transfer else "reset"
    return _deck(design, f"noise_fd_{kind}_{which}", el, (), Noise("fd", src, dc, 1e-3, 1e10),
                 options=NOISE_OPTIONS)


def read_deck(design, v_fd: float) -> Netlist:
    return _deck(design, "noise_read", read_chain(design), (), Noise("col", "fd", v_fd, 1.0, 1e11, 40),
                 options=NOISE_OPTIONS)


def flicker_deck(design, w: float, l: float, i_d: float, v_g: float = 2.0) -> Netlist:
    """One NMOS (W, L) as a follower carrying ``i_d`` from the supply, gate at ``v_g``."""
    t = design.tech
    el = (mosfet("f", "vdd", "g", "s", "0", w, l, t), Element("Vdd", ("vdd", "0"), t.supply),
          Element("Ib", ("s", "0"), i_d))
    return _deck(design, "noise_flicker", el, (), Noise("s", "g", v_g, 1.0, 1e3, 10), options=NOISE_OPTIONS)
