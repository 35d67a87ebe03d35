"""Shutter timing: per-row reset, exposure and read times ([Thesis2019] eq. 2.14).

A row takes ``T_row = row_length / f_pixclk`` to read (row_length counts the
horizontal blanking pixels); a frame ``T_readout = (N_row + v_blank) T_row``
(vertical blanking in rows).

- ``global``: every row exposes over [0, t_int]; the charge waits on the storage
  node until the row is read at ``t_int + t0 + r T_row`` (wait t0 + r T_row).
- ``rolling_readout`` (3T, no extra reset): row r is read at ``r T_row`` and reset
  right after, so it integrates a whole frame: [r T_row - T_frame, r T_row].
- ``rolling_shutter`` (electronic rolling shutter): an extra reset ``t_int`` before
  the read: [r T_row - t_int, r T_row]; t_int is a whole number of rows.

``scan = "down"`` reads row 0 first; ``"up"`` reads the last row first (the
second sensor of the two-sensor compensation).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError

MODES = ("global", "rolling_readout", "rolling_shutter")
SCANS = ("down", "up")


@dataclass(frozen=True)
class ShutterTiming:
    mode: str
    n_rows: int
    row_length: int          # pixel clocks per row, blanking included
    f_pixclk: float          # Hz
    t_int: float = 0.0       # s (global and rolling_shutter)
    v_blank: int = 0         # rows of vertical blanking
    t0: float = 0.0          # s, global shutter: from the end of exposure to the first row's read
    scan: str = "down"

    def __post_init__(self):
        checks = [("mode", self.mode, self.mode in MODES, f"one of {', '.join(MODES)}"),
                  ("scan", self.scan, self.scan in SCANS, "down or up"),
                  ("n_rows", self.n_rows, int(self.n_rows) >= 1, "an integer >= 1"),
                  ("row_length", self.row_length, int(self.row_length) >= 1, "pixel clocks >= 1"),
                  ("f_pixclk", self.f_pixclk, self.f_pixclk > 0, "a clock > 0 Hz"),
                  ("v_blank", self.v_blank, int(self.v_blank) >= 0, "rows >= 0"),
                  ("t0", self.t0, self.t0 >= 0, "a delay >= 0 s")]
        if self.mode != "rolling_readout":
            checks.append(("t_int", self.t_int, self.t_int > 0, "an exposure > 0 s"))
        for name, value, ok, allowed in checks:
            if not ok:
                raise ConfigError("shutter timing", name, value, allowed)
        if self.mode == "rolling_shutter" and self.t_int > self.t_frame + 1e-15:
            raise ConfigError("shutter timing", "t_int", self.t_int,
                              f"an exposure no longer than the frame ({self.t_frame:g} s)")

    @property
    def t_row(self) -> float:
        return self.row_length / self.f_pixclk

    @property
    def t_frame(self) -> float:
        """T_readout = (N_row + v_blank) Row_length / f_pixclk (thesis eq. 2.14 with blanking)."""
        return (self.n_rows + self.v_blank) * self.t_row

    def order(self) -> np.ndarray:
        """Read position of each row (0 = read first)."""
        r = np.arange(self.n_rows)
        return r if self.scan == "down" else self.n_rows - 1 - r

    def read_times(self) -> np.ndarray:
        if self.mode == "global":
            return self.t_int + self.t0 + self.order() * self.t_row
        return self.order() * self.t_row

    def exposure(self) -> np.ndarray:
        """(N_row, 2): start and end of each row's open-shutter exposure."""
        read = self.read_times()
        if self.mode == "global":
            return np.column_stack([np.zeros(self.n_rows), np.full(self.n_rows, self.t_int)])
        t_acc = self.t_frame if self.mode == "rolling_readout" else self.t_int
        return np.column_stack([read - t_acc, read])

    def reset_times(self) -> np.ndarray:
        return self.exposure()[:, 0]

    def storage_wait(self) -> np.ndarray:
        """Time each row's charge waits on the storage node before it is read (0 for rolling)."""
        return self.read_times() - self.exposure()[:, 1]
