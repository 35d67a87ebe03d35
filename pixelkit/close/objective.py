"""What ``pixelkit close`` optimises once every spec passes: ``[close] objective``.

- ``power``: the chip's power (the figure ``power_chip``, SPICE supply currents) at the nominal
  condition (the design's corner and temperature, nominal supply);
- a figure a spec can name (``max full_well_primary``, ``min read_noise_secondary``): its value
  at the nominal condition;
- ``area``: the gate area W x L of the five transistors (EC, TG, RST, SF, RS) of every subpixel
  of one dual pixel (1 + ``secondary_per_pixel`` subpixels): the silicon the devices take from
  the photodiodes; of a pixel read by role, its family's (the 4T's TG, RST, SF and RS; a netlist
  pixel has none: refused when the file loads). A closed form, no simulation;
- a knob (``max pixel.v_fd_reset``): its own value.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ..verify.close_table import figures_of, value_of

_PIXEL_DEVICES = ("ec", "tg", "rst", "sf", "rs")


def gate_area(design) -> float:
    """m2 of gate per dual pixel, or per pixel of a role family (see the module docstring)."""
    if hasattr(design, "gate_area"):
        return design.gate_area()
    d = design.pixel.devices
    per_subpixel = sum(getattr(d, f"{n}_w") * getattr(d, f"{n}_l") for n in _PIXEL_DEVICES)
    return per_subpixel * (1 + design.secondary_per_pixel)


@dataclass(frozen=True)
class Objective:
    sense: str        # "min" | "max"
    what: str         # a figure name, "area" or a knob key
    figures: dict = field(default_factory=dict, repr=False, compare=False)   # the design's figures (by name)

    @property
    def figure(self) -> str | None:
        """The figure measured at the nominal condition, or None for a closed form."""
        return self.what if self.what in self.figures else None

    @property
    def unit(self) -> str:
        if self.figure:
            return self.figures[self.figure].unit
        return "um2" if self.what == "area" else ""

    def value(self, design, nominal_figures: dict | None) -> float | None:
        """The objective's value (SI) of ``design``; a figure from ``nominal_figures``."""
        if self.figure:
            return (nominal_figures or {}).get(self.figure)
        if self.what == "area":
            return gate_area(design)
        return float(value_of(design, self.what))

    def label(self) -> str:
        return f"{self.sense} {self.what}"


def of(design) -> Objective:
    sense, what = design.close.goal
    return Objective(sense, what, figures_of(design))
