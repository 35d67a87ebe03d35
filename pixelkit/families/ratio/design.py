"""Design file of the ratio pixel (``designs/ratio_pixel.toml``), validated on load."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ...errors import ConfigError
from ...schema import ident, integer, named, num, qty, table, text
from ...verify.spec import Spec, VerifySettings, check_conditions
from ..base import DrawnPd, FamilyDesign, load_family_design


@dataclass(frozen=True)
class Loop:
    """The four identical loop NMOS (M1-M4) and the source level of the diode pair."""
    w: float = qty("m", 4e-6, gt=0, doc="loop NMOS width (paper: 2 fingers of 2 um x 1 um)")
    l: float = qty("m", 1e-6, gt=0, doc="loop NMOS length")
    v_source: float = qty("V", 0.4, ge=0, le=1.5, doc="source level of M3/M4 (tail headroom)")
    tail_w: float = qty("m", 4e-6, gt=0, doc="tail current-source NMOS (and its column mirror)")
    tail_l: float = qty("m", 4e-6, gt=0, doc="tail current-source NMOS length")
    sel_w: float = qty("m", 1e-6, gt=0, doc="row-select switches")
    sel_l: float = qty("m", 0.5e-6, gt=0, doc="row-select switches: length")


@dataclass(frozen=True)
class Photodiodes(DrawnPd):
    pd_width: float = qty("m", 7e-6, gt=0, doc="width of each photodiode of a pair")
    pd_height: float = qty("m", 7e-6, gt=0, doc="height of each photodiode of a pair")
    pd_model: str = ident("diode_pd2nw_03v3",
                          doc="p+/n-well junction: its anode feeds the diode-connected M3/M4")


@dataclass(frozen=True)
class Readout:
    i_bias: float = qty("A", 20e-9, gt=0, le=10e-6, doc="loop bias (paper: ~20 nA nominal)")
    i_bias_high: float = qty("A", 100e-9, gt=0, le=10e-6, doc="the paper's 'too high' bias (~100 nA)")
    c_par: float = qty("F", 30e-15, gt=0, le=10e-12, doc="column parasitic capacitance (each of C_par+/-)")
    counter_bits: int = integer(5, ge=1, le=16, doc="bits of the column counter (the paper's 5)")
    lsb_per_tau: float = num(1.0, ge=1.0, le=100, doc="lambda in T_LSB = lambda tau (paper: 1 is optimal)")
    inv_wn: float = qty("m", 1e-6, gt=0, doc="column inverter NMOS width (trips at V_th)")
    inv_wp: float = qty("m", 2e-6, gt=0, doc="column inverter PMOS width")
    inv_l: float = qty("m", 0.5e-6, gt=0, doc="column inverter length")
    v_select: float = qty("V", 1.4, gt=0, le=5, doc="row-select high level: the select NMOS cascodes the loop outputs")
    v_clamp_gate: float = qty("V", 1.6, ge=0, le=5, doc="gate of the column clamp (holds a tripped column)")
    clamp_w: float = qty("m", 1e-6, gt=0, doc="column clamp width")
    clamp_l: float = qty("m", 0.5e-6, gt=0, doc="column clamp length")
    pre_w: float = qty("m", 2e-6, gt=0, doc="precharge PMOS")
    pre_l: float = qty("m", 0.5e-6, gt=0, doc="precharge PMOS length")

    def validate(self, path, source):
        if self.i_bias_high <= self.i_bias:
            raise ConfigError(source, f"{path}.i_bias_high", self.i_bias_high,
                              f"a bias above i_bias ({self.i_bias:g} A)")


@dataclass(frozen=True)
class Array:
    """The array the power figures scale to: the paper's prototype is 32 x 32 at 9600 frames/s."""
    rows: int = integer(32, ge=1, le=100000, doc="pixel rows (read one at a time, back to back)")
    cols: int = integer(32, ge=1, le=100000, doc="pixel columns (each with its four column lines, "
                                                  "two counters and a bias mirror)")
    frame_rate: float = qty("Hz", 9600.0, gt=0, doc="frames per second: a row slot lasts 1 / (rows x frame_rate)")


@dataclass(frozen=True)
class Experiment:
    ratio_intensity: float = num(10.0, gt=1, le=1000, doc="ratio used for the intensity sweep")


@dataclass(frozen=True)
class RatioDesign(FamilyDesign):
    family: str = text(choices=("ratio",), doc="the ratio-based HDR pixel [Sun2016]")
    loop: Loop = table(Loop, default=Loop, doc="the translinear loop of each photodiode pair")
    photodiodes: Photodiodes = table(Photodiodes, default=Photodiodes, doc="the photodiodes")
    readout: Readout = table(Readout, default=Readout, doc="bias, column capacitance, counter and column devices")
    experiment: Experiment = table(Experiment, default=Experiment, doc="the family's experiment")
    array: Array = table(Array, default=Array, doc="array size and frame rate (pixelkit verify's power)")
    verify: VerifySettings = table(VerifySettings, default=VerifySettings,
                                   doc="the sign-off grid of pixelkit verify (no Monte Carlo for this family yet)")
    spec: tuple = named(Spec, doc="specifications: one [spec.<name>] table each; this family measures "
                                  "power_chip only (docs/verify.md)")


#: the [spec] figures this family measures
FIGURES = ("power_chip",)


def load_ratio_design(path: str | Path) -> RatioDesign:
    d = load_family_design(RatioDesign, path)
    for s in d.spec:
        if s.fig.name not in FIGURES:
            raise ConfigError(d.source, f"spec.{s.name}" + (".figure" if s.figure else ""), s.fig.name,
                              f"a figure the ratio family measures: {', '.join(FIGURES)}")
    check_conditions(d, d.tech)
    return d
