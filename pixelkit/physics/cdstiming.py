"""The rolling-shutter sequence of a 4T pixel read with true correlated double sampling (pure
arithmetic: the benches draw it, the models read its instants).

One *frame* of one pixel, times from the frame's start:

    0 .. t_shutter              shutter: RST and TG on together, the PPD empties through FD into the
                                reset drain; exposure starts when TG opens (end of its pulse)
    ... t_exp ...               exposure (light on the PPD)
    read (row time t_row):      RS on; RST pulses (FD reset); SHR samples the reset level; TG pulses
                                (transfer: exposure ends when TG opens); SHS samples the signal
                                level; RS off

The reset sample and the signal sample read the same FD reset, so the difference
``V(SHR) - V(SHS)`` holds the transferred charge without FD's kT/C (true CDS). Exposure runs
from the shutter TG's falling edge to the read TG's falling edge. Edges take ``edge``.

The benches light the pixel as a pulsed source does in a lag measurement: on from the shutter TG's
fall to the read TG's rise (``Frame.light``, ``t_exp - t_tg`` long), so every photo-electron of a
frame is in the PPD when its read transfer starts, and none arrives while a transfer runs.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class CdsTiming:
    t_rst: float = 0.5e-6       # RST pulse of the read
    t_tg: float = 1.0e-6        # TG pulse (read and shutter)
    t_sh: float = 1.0e-6        # SHR / SHS sample pulses
    t_settle: float = 0.5e-6    # after RS rises / RST falls / TG falls, before a sample opens
    edge: float = 10e-9

    @property
    def t_shutter(self) -> float:
        """Shutter length: RST on, TG pulse inside it with ``t_settle`` margins."""
        return self.t_tg + 2 * self.t_settle

    @property
    def shutter_tg(self) -> tuple:
        return (self.t_settle, self.t_settle + self.t_tg)

    # read phases, from the read's start
    @property
    def rst(self) -> tuple:
        return (self.t_settle, self.t_settle + self.t_rst)

    def _after(self, phase: tuple, settle: float, length: float) -> tuple:
        """A pulse ``length`` long that rises ``settle`` after ``phase`` has fallen (its edge included)."""
        a = phase[1] + self.edge + settle
        return (a, a + length)

    @property
    def shr(self) -> tuple:
        return self._after(self.rst, self.t_settle, self.t_sh)

    @property
    def tg(self) -> tuple:
        return self._after(self.shr, self.t_settle / 2, self.t_tg)

    @property
    def shs(self) -> tuple:
        return self._after(self.tg, self.t_settle, self.t_sh)

    @property
    def t_row(self) -> float:
        """One row's read: RS on for this long."""
        return self.shs[1] + self.edge + self.t_settle

    @property
    def cds_interval(self) -> float:
        """Time between the two samples (the switches open at the ends of SHR and SHS)."""
        return self.shs[1] - self.shr[1]

    def frame(self, t_exp: float) -> "Frame":
        return Frame(self, t_exp)


@dataclass(frozen=True)
class Frame:
    """One frame's instants, from the frame's start."""
    timing: CdsTiming
    t_exp: float

    @property
    def t_read(self) -> float:
        """Start of the read: the read's TG falls ``t_exp`` after the shutter TG."""
        t = self.timing
        return t.shutter_tg[1] + self.t_exp - t.tg[1]

    @property
    def length(self) -> float:
        return self.t_read + self.timing.t_row

    def at(self, phase: tuple) -> tuple:
        return (self.t_read + phase[0], self.t_read + phase[1])

    @property
    def light(self) -> tuple:
        """(on, off) of the frame's light, from the frame's start: shutter TG fall to read TG rise."""
        t = self.timing
        return (t.shutter_tg[1] + t.edge, self.t_read + t.tg[0])

    @property
    def light_time(self) -> float:
        on, off = self.light
        return off - on

    @property
    def t_hold(self) -> float:
        """An instant when both samples are held (the end of the row)."""
        return self.t_read + self.timing.t_row - self.timing.edge

    @property
    def min_exposure(self) -> float:
        """The shortest exposure: the read starts once the shutter has ended."""
        t = self.timing
        return t.t_shutter - t.shutter_tg[1] + t.tg[1]
