"""Decks for ngspice ``.noise`` of the SC AFE at its two phase operating points.

The kit's AFE cell (``afe.sc_afe``, its elements flattened so the probe can see the
internal nodes) with the design's op-amp (the macromodel carries its input noise,
``opamp.opamp_macro``) and the CMOS switches held on or off by DC gate levels:

- ``phase1_deck``: autozero (p1 on). The output is the combination of the nodes the
  p1 switches leave, ``v(c) - v(x) / beta`` (noiseless VCVS probe), which is what the
  end of phase 2 makes of them (``physics.afe_noise``): its integral over frequency
  is the variance sampled into the output when p1 opens (sampled-noise theory).
- ``phase2_deck``: amplification (p2 on): the output spectrum. The nodes p1 left
  floating (x, vm) get their DC from 1e15 Ohm *noiseless* resistors (``noisy=0``),
  which act only below 1 mHz.

The input ``in`` is the ``.noise`` source (an ideal, noiseless level).
"""
from __future__ import annotations

from ..physics.afe_noise import beta
from ..spice.netlist import Element, Netlist, Param
from .afe import sc_afe
from .noisebench import NOISE_OPTIONS, Noise
from .opamp import opamp
from .testbench import _deck

#: DC path for the nodes phase 2 leaves floating (noiseless, Ohm)
R_DC = 1e15


def _afe(design, p1_on: bool) -> list:
    a, vdd = design.afe, design.tech.supply
    values = {"c11": a.c11, "c12": a.c12, "c13": a.c13}
    cell = [Element(e.name, e.nodes, values[e.value.name] if isinstance(e.value, Param) else e.value, e.params)
            for e in sc_afe(design).elements]
    hi, lo = (vdd, 0.0) if p1_on else (0.0, vdd)
    return [*cell, Element("Vdd", ("vdd", "0"), vdd), Element("Vref", ("vref", "0"), a.vref),
            Element("Vp1", ("p1", "0"), hi), Element("Vp1b", ("p1b", "0"), lo),
            Element("Vp2", ("p2", "0"), lo), Element("Vp2b", ("p2b", "0"), hi)]


def phase1_deck(design, f_stop: float = 1e11) -> Netlist:
    el = _afe(design, p1_on=True) + [
        Element("Eprx", ("px", "0", "x", "0"), -1.0 / beta(design)),
        Element("Eprobe", ("probe", "px", "c", "0"), 1.0)]
    return _deck(design, "noise_afe_phase1", el, (opamp(design),),
                 Noise("probe", "in", design.afe.vref, 1.0, f_stop, 20), options=NOISE_OPTIONS)


def phase2_deck(design, f_stop: float = 1e11) -> Netlist:
    el = _afe(design, p1_on=False) + [
        Element("Rdcx", ("x", "vref"), R_DC, (("noisy", 0),)),
        Element("Rdcvm", ("vm", "vref"), R_DC, (("noisy", 0),))]
    return _deck(design, "noise_afe_phase2", el, (opamp(design),),
                 Noise("out", "in", design.afe.vref, 1.0, f_stop, 20), options=NOISE_OPTIONS)
