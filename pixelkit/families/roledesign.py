"""What every pixel read by role shares in its design file (families ``pixel4t`` and ``netlist``):
the drive levels, the column with its sample-and-hold, the read timing, the array, the short-window
experiment, the sign-off grid and its specs (``verify.figures.ROLE_FIGURES``).

A design of either family names a pixel (the kit's generator, or a designer's subcircuit) and
these tables; ``rolepix`` measures it and ``pixelkit verify`` signs it off with the same code.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

from ..errors import ConfigError
from ..schema import integer, named, num, qty, table, text
from ..verify.close_table import CloseSettings, check as check_close
from ..verify.spec import RoleSpec, VerifySettings, check_conditions
from .base import FamilyDesign, load_family_design

_WL = (0.1e-6, 1e-3)


@dataclass(frozen=True)
class Levels:
    """The levels the row drivers put on the pixel's gates, and the reset drain."""
    gate_drive: str = text("supply", choices=("supply", "boosted"),
                           doc="supply: RST and TG go high to the supply (they follow it at every supply condition); "
                               "boosted: to the regulated rail v_gate")
    v_gate: float | None = qty("V", None, gt=0, plausible=(0.5, 40.0),
                               doc="the boosted RST / TG high level (gate_drive = \"boosted\")")
    v_rst: float | None = qty("V", None, gt=0, plausible=(0.1, 40.0),
                              doc="reset drain (FD reset level): absent = the supply (follows it); a value = a "
                                  "regulated reference")
    tg_low: float = qty("V", 0.0, ge=-5.0, le=5.0, doc="TG low level during exposure (0 V; negative values need a "
                                                       "negative rail: lower TG-edge dark current)")
    tg_high: float | None = qty("V", None, gt=0, plausible=(0.5, 40.0),
                                doc="TG high level: absent = the gate level of RST (the supply or v_gate); a value = "
                                    "its own regulated rail (the transfer barrier follows it: docs/pixel4t.md)")

    def v_rst_for(self, supply: float) -> float:
        return supply if self.v_rst is None else self.v_rst

    def validate(self, path, source):
        if self.gate_drive == "boosted" and self.v_gate is None:
            raise ConfigError(source, f"{path}.v_gate", None, "a level with gate_drive = \"boosted\"")
        if self.gate_drive == "supply" and self.v_gate is not None:
            raise ConfigError(source, f"{path}.v_gate", self.v_gate, "no value with gate_drive = \"supply\"")


@dataclass(frozen=True)
class Column:
    """The column line: its current-source load, capacitance and sample-and-hold pair."""
    bias: float = qty("A", 2e-6, gt=0, le=1e-3, plausible=(1e-9, 1e-3), doc="source-follower load current")
    load_w: float = qty("m", 2e-6, gt=0, plausible=_WL, doc="load NMOS (and its bias mirror) width")
    load_l: float = qty("m", 2e-6, gt=0, plausible=_WL, doc="load NMOS length")
    cap: float = qty("F", 1e-12, gt=0, plausible=(1e-16, 1e-8), doc="column line capacitance")
    sh_cap: float = qty("F", 1e-12, gt=0, plausible=(1e-16, 1e-8),
                        doc="each sample-and-hold capacitor (SHR and SHS): its kT/C is in the read noise")
    sw_w: float = qty("m", 1e-6, gt=0, plausible=_WL, doc="S/H switch (NMOS) width")
    sw_l: float = qty("m", 0.5e-6, gt=0, plausible=_WL, doc="S/H switch length")


@dataclass(frozen=True)
class Timing:
    """The row read (physics.cdstiming): RST pulse, SHR, TG pulse, SHS."""
    t_rst: float = qty("s", 0.5e-6, gt=0, plausible=(1e-9, 1e-3), doc="RST pulse of the read")
    t_tg: float = qty("s", 1e-6, gt=0, plausible=(1e-9, 1e-3), doc="TG pulse (read and shutter): the transfer time")
    t_sh: float = qty("s", 1e-6, gt=0, plausible=(1e-9, 1e-3), doc="SHR / SHS sample pulses")
    t_settle: float = qty("s", 0.5e-6, gt=0, plausible=(1e-9, 1e-3), doc="settling before each sample")
    edge: float = qty("s", 10e-9, gt=0, plausible=(1e-12, 1e-5), doc="control edges")


@dataclass(frozen=True)
class Array:
    rows: int = integer(480, ge=1, le=100000, doc="rows (read one after another: the frame time)")
    cols: int = integer(640, ge=1, le=100000, doc="columns (one load and S/H pair each)")
    frame_rate: float = qty("Hz", 30.0, gt=0, plausible=(1e-3, 1e6), doc="frames per second")
    t_int: float = qty("s", 10e-3, gt=0, le=10.0, plausible=(1e-7, 10.0),
                       doc="integration time (the dark-current figure's exposure)")

    def validate(self, path, source):
        if self.t_int > 1.0 / self.frame_rate:
            raise ConfigError(source, f"{path}.t_int", self.t_int, f"at most the frame time 1 / frame_rate "
                              f"({1.0 / self.frame_rate:g} s)")


@dataclass(frozen=True)
class Experiment:
    """The short-window decks (conversion gain, full well, lag)."""
    t_window: float = qty("s", 20e-6, gt=0, le=1e-2, plausible=(1e-7, 1e-2), doc="exposure of those decks")
    small_fraction: float = num(0.05, gt=0, lt=0.5, doc="the small signal, a fraction of the full well")
    lag_fraction: float = num(0.5, gt=0, le=1.0, doc="the bright frame before the lag frame, a fraction of the full well")
    prnu_pixels: int = integer(16, ge=4, le=256, doc="pixels of the PRNU deck (each its own mismatch draw)")


@dataclass(frozen=True)
class RoleDesign(FamilyDesign):
    levels: Levels = table(Levels, default=Levels, doc="gate and reset-drain levels")
    column: Column = table(Column, default=Column, doc="the column line and its sample-and-hold")
    timing: Timing = table(Timing, default=Timing, doc="the row read with true CDS")
    array: Array = table(Array, default=Array, doc="array size, frame rate, integration time")
    experiment: Experiment = table(Experiment, default=Experiment, doc="the short-window measurement decks")
    verify: VerifySettings = table(VerifySettings, default=VerifySettings,
                                   doc="the sign-off grid of pixelkit verify: corners, temperatures, supplies, Monte Carlo")
    spec: tuple = named(RoleSpec, doc="specifications on the figures of a pixel read by role (docs/verify.md)")
    close: CloseSettings | None = table(CloseSettings, None, doc="the knobs pixelkit close may move, their bounds "
                                        "and the objective (docs/close.md)")
    raw: dict = field(default=None, metadata=dict(kind="skip"), repr=False, compare=False)

    @property
    def suite(self):
        """What ``pixelkit verify`` measures on this design (``rolepix.suite``)."""
        from ..rolepix import suite
        return suite

    def cell(self):
        """The pixel as a role cell (``circuits.roles.PixelCell``): each family says how."""
        raise NotImplementedError

    def gate_area(self) -> float | None:
        """m2 of transistor gate in one pixel (``close``'s ``area`` objective); None: the family does not know."""
        return None

    def reloaded(self, raw: dict):
        """This design with its file's content replaced by ``raw`` (``sweep.space.design_with``), loaded by its
        family's loader at the same path (each family says how)."""
        raise NotImplementedError


def load_role_design(cls, path, *checks, raw: dict | None = None):
    """Load a design of role family ``cls``: the family's own ``checks`` (each ``check(design)``), then the
    levels against the technology, the sign-off grid's conditions and the ``[close]`` table's knobs."""
    d = load_family_design(cls, path, raw)
    for check in checks:
        check(d)
    check_levels(d)
    check_conditions(d, d.tech)
    if d.close is not None:   # the knobs against this design's keys (bounds in SI), as the dual pixel's
        d = replace(d, close=check_close(d.close, d, d.source, d.raw))
    return d


def check_levels(design) -> None:
    """Levels against the technology: no drain or gate above what the devices take."""
    tech, lv = design.tech, design.levels
    if lv.v_rst is not None and lv.v_rst > tech.supply:
        raise ConfigError(design.source, "levels.v_rst", lv.v_rst, f"a level no higher than the supply ({tech.supply:g} V)")
    gmax = tech.mos.v_gate_max or 1.1 * tech.supply
    for key in ("v_gate", "tg_high"):
        v = getattr(lv, key)
        if v is not None and v > gmax:
            raise ConfigError(design.source, f"levels.{key}", v, f"at most the devices' rated {gmax:.4g} V")
