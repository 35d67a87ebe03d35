"""Design file of the WDR pixel (``designs/wdr_pixel.toml``), validated on load."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ...errors import ConfigError
from ...schema import integer, qty, table, text
from ..base import DrawnPd, FamilyDesign, load_family_design


@dataclass(frozen=True)
class Pixel(DrawnPd):
    pd_width: float = qty("m", 10e-6, gt=0, doc="photodiode width")
    pd_height: float = qty("m", 10e-6, gt=0, doc="photodiode height")
    c_int: float = qty("F", 200e-15, gt=0, le=10e-12, doc="integration capacitor")
    v_reset: float = qty("V", 2.0, gt=0, doc="reset level of the integration node")
    v0: float = qty("V", 1.2, gt=0, doc="exposure threshold V0 of the comparator")
    v_ab: float = qty("V", 0.9, ge=0, doc="reset gate low level: anti-blooming clamp of the PD")
    sw_w: float = qty("m", 0.5e-6, gt=0, doc="reset / integration switches")
    sw_l: float = qty("m", 0.5e-6, gt=0, doc="reset / integration switches: length")

    def validate(self, path, source):
        if self.v0 >= self.v_reset:
            raise ConfigError(source, f"{path}.v0", self.v0, f"a threshold below v_reset ({self.v_reset:g} V)")


@dataclass(frozen=True)
class Comparator:
    """Transistor-level comparator: NMOS pair, PMOS mirror, NMOS tail, two inverters."""
    i_tail: float = qty("A", 200e-9, gt=0, le=100e-6, doc="tail current of the input pair (from a column mirror)")
    in_w: float = qty("m", 1e-6, gt=0, doc="input-pair NMOS width")
    in_l: float = qty("m", 1e-6, gt=0, doc="input-pair NMOS length")
    load_w: float = qty("m", 1e-6, gt=0, doc="PMOS mirror load width")
    load_l: float = qty("m", 1e-6, gt=0, doc="PMOS mirror load length")
    tail_w: float = qty("m", 1e-6, gt=0, doc="tail NMOS width")
    tail_l: float = qty("m", 2e-6, gt=0, doc="tail NMOS length")


@dataclass(frozen=True)
class Coding:
    """Time-to-voltage coding: signal1 (V-waves), signal2 (ramp), read-in switches, C1/C2."""
    t_unit: float = qty("s", 64e-6, gt=0, le=1.0, doc="T: the shortest detectable exposure")
    steps: int = integer(8, ge=2, le=12, doc="N: signal1 flips at T, 2T, ..., 2^N T")
    v_low: float = qty("V", 1.0, gt=0, doc="low level of the coding waves signal1 / signal2")
    v_high: float = qty("V", 2.0, gt=0, doc="high level of the coding waves")
    c_store: float = qty("F", 200e-15, gt=0, le=10e-12, doc="C1 = C2")
    sw_w: float = qty("m", 0.5e-6, gt=0, doc="PMOS read-in switches (n-well at v_high)")
    sw_l: float = qty("m", 0.28e-6, gt=0, doc="PMOS read-in switches: length")
    t_delay: float = qty("s", 0.3e-6, gt=0, le=1e-3, doc="delay of the sampling pulse (R C ln 2 of its RC)")
    delay_c: float = qty("F", 100e-15, gt=0, le=10e-12, doc="C of the delay RC; R = t_delay / (C ln 2)")

    def validate(self, path, source):
        if self.v_high <= self.v_low:
            raise ConfigError(source, f"{path}.v_high", self.v_high, f"a level above v_low ({self.v_low:g} V)")


@dataclass(frozen=True)
class Noise:
    """The readout after the pixel (not in the circuit); the pixel's own noise is derived (wdr/model.py)."""
    v_read: float = qty("V", 0.5e-3, ge=0, doc="noise of the readout after the pixel (column amplifier, ADC), "
                                                  "referred to the node (rms); reset, exposure sample and dark "
                                                  "shot noise are derived")


@dataclass(frozen=True)
class WdrDesign(FamilyDesign):
    family: str = text(choices=("wdr",), doc="the WDR pixel with self-adjusting exposure [Zhou2017]")
    pixel: Pixel = table(Pixel, default=Pixel, doc="photodiode, integration capacitor, threshold and switches")
    comparator: Comparator = table(Comparator, default=Comparator, doc="the in-pixel comparator against V0")
    coding: Coding = table(Coding, default=Coding, doc="the time-to-voltage coding")
    noise: Noise = table(Noise, default=Noise, doc="the noise floor used for the dynamic range")


def load_wdr_design(path: str | Path) -> WdrDesign:
    design = load_family_design(WdrDesign, path)
    supply = design.tech.supply
    for table_, f in (("pixel", "v_reset"), ("pixel", "v0"), ("coding", "v_high")):
        v = getattr(getattr(design, table_), f)
        if v >= supply:
            raise ConfigError(str(design.source), f"{table_}.{f}", v, f"a level below the supply ({supply:g} V)")
    return design
