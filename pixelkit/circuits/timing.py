"""The global-shutter sequence: its switch intervals and sample instants (pure arithmetic: the
models use it too; ``testbench.waveform`` draws the intervals as PWL sources).

    0 .. t_reset + t_hold   EC on (PD reset), RST on (FD reset)
    t_reset + t_hold        EC opens: exposure starts (all pixels of the array)
    t_tx - t_tg - t_gap     RST opens (FD released before the transfer)
    t_tx - t_tg .. t_tx     TG on: global transfer; exposure ends when TG opens
    t_tx .. t_read          storage: the charge waits on FD (t_pre + t_store); with
                            ``ec_hold`` EC closes again after the transfer and holds
                            the PD in reset (anti-blooming), else the PD keeps
                            integrating and can overflow
    t_read + r t_row        row r: RS on; S1 samples the signal; RST pulses (FD
                            reset); S2 samples the reset level (non-correlated
                            double sampling, thesis fig. 3.3); RS off

Each array has its own row time 1/f_read (defaults 500 kHz primary, 1 MHz
secondary). Edges take ``edge`` seconds; levels are 0 and the supply.

The two arrays have their own exposure (thesis: 1 ms primary, 12 ms secondary);
``aligned`` gives the shorter one a ``t_hold`` so both transfer at the same
instant and are read out together. ``t_store`` adds storage time before the
first row: the wait of row ``r`` of a frame is ``t_pre + r t_row``.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class GsTiming:
    t_exp: float
    t_row: float
    rows: int = 1
    t_reset: float = 1e-6
    t_tg: float = 0.5e-6
    t_gap: float = 0.3e-6
    edge: float = 10e-9
    t_pre: float = 0.3e-6  # from end of transfer to the first row
    t_hold: float = 0.0    # EC held on after t_reset: the exposure starts later
    t_store: float = 0.0   # extra storage on FD before the first row is read
    ec_hold: bool = False  # EC resets the PD again during storage

    @property
    def t_start(self) -> float:
        """EC opens: the start of exposure."""
        return self.t_reset + self.t_hold

    @property
    def t_tx(self) -> float:
        """TG opens: the end of exposure."""
        return self.t_start + self.t_exp

    @property
    def t_read(self) -> float:
        return self.t_tx + self.t_pre + self.t_store

    def t_wait(self, r: int) -> float:
        """Time the charge of row ``r`` waits on FD from the transfer to its signal sample."""
        return self.t_signal(r) - self.t_tx

    def row(self, r: int) -> float:
        return self.t_read + r * self.t_row

    def s1_window(self, r: int):
        t0 = self.row(r)
        return t0 + 0.1 * self.t_row, t0 + 0.4 * self.t_row

    def rst_window(self, r: int):
        t0 = self.row(r)
        return t0 + 0.45 * self.t_row, t0 + 0.55 * self.t_row

    def s2_window(self, r: int):
        t0 = self.row(r)
        return t0 + 0.6 * self.t_row, t0 + 0.9 * self.t_row

    def t_signal(self, r: int) -> float:
        """Instant the signal level is taken (end of S1)."""
        return self.s1_window(r)[1]

    def t_reset_level(self, r: int) -> float:
        """Instant the reset level is taken (end of S2)."""
        return self.s2_window(r)[1]

    @property
    def t_stop(self) -> float:
        return self.row(self.rows) + 0.05 * self.t_row

    # switch intervals ------------------------------------------------------
    def ec(self):
        on = [(0.0, self.t_start)]
        if self.ec_hold:
            on.append((self.t_tx + self.t_gap, self.t_stop))
        return on

    def tg(self):
        return [(self.t_tx - self.t_tg, self.t_tx)]

    def rst(self, r: int):
        return [(0.0, self.t_tx - self.t_tg - self.t_gap), self.rst_window(r)]

    def rs(self, r: int):
        t0 = self.row(r)
        return [(t0 + 0.02 * self.t_row, t0 + 0.98 * self.t_row)]

    def row_list(self, rows=None) -> list:
        """Rows to clock: all (None), the first ``rows`` (an int), or the given row indices."""
        if rows is None:
            return list(range(self.rows))
        return list(range(rows)) if isinstance(rows, int) else list(rows)

    def s1(self, rows=None):
        return [self.s1_window(r) for r in self.row_list(rows)]

    def s2(self, rows=None):
        return [self.s2_window(r) for r in self.row_list(rows)]


def timings(design, t_exp: float, rows: int = 1, t_exp_secondary: float | None = None,
            t_store: float = 0.0, ec_hold: bool = False) -> dict:
    """Per-array GS timing, each array with its own row time.

    ``t_exp`` is the primary exposure; the secondary's is ``t_exp_secondary``
    (default: the same window). The shorter exposure starts later (EC held) so
    both arrays transfer together; ``t_store`` delays the first row's read.
    """
    t_s = t_exp if t_exp_secondary is None else t_exp_secondary
    longest = max(t_exp, t_s)
    common = dict(rows=rows, t_store=t_store, ec_hold=ec_hold)
    return {"primary": GsTiming(t_exp, 1.0 / design.primary.f_read, t_hold=longest - t_exp, **common),
            "secondary": GsTiming(t_s, 1.0 / design.secondary.f_read, t_hold=longest - t_s, **common)}
