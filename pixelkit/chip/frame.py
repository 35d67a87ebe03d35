"""One frame of the pixel arrays, simulated whole or split into independent tiles.

What is independent (and why the split is exact up to the simulator's numerics):

- the two arrays have their own control lines, column buses and column-load bias (an ideal
  current into a diode-connected NMOS per array, as each array's own bias generator): they
  share only ideal sources. (One bias node shared by both arrays couples them through the
  loads' Cgd while the columns slew, ~0.1 mV with the AFE, and no split could keep that);
- the columns of an array share row lines (ideal sources), supplies and the array's bias
  node, so a row's deck keeps all the array's columns;
- during exposure every pixel is on its own; during read-out only the selected row
  drives a column (the other rows' RS switches are off and their lines static).

So a frame splits into one deck per array and row (``split="rows"``), each holding
that row's subpixels, all their columns (load, and with the AFE: S1X/S2X and the SC
AFE) and the row's own controls at the row's own time in the frame; the deck stops
when its row has been read. With the AFE the previous row is simulated too (``lead``): the
column and C11 enter a row holding the previous row's reset level, and for large signals
the column does not settle within S1, so the row's signal depends on it. Cost then grows
as rows x columns instead of the whole deck's ~rows^1.8 (a whole-column deck re-solves every row's pixels at every row's
edges). ``split="none"`` simulates the frame as one deck (the reference); the test
and ``pixelkit array --check`` compare both.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..circuits.array import KINDS, PREFIX, Tile, array_bench, frame_shape, frame_timings
from ..errors import ConfigError, SimulationError
from ..sweep.executors import run_tasks

SPLITS = ("rows", "none")
#: Largest time step of a frame deck: 1/20 of the shorter row time (50 ns for 1 MHz). PWL
#: edges are breakpoints, so switching is still resolved; the flat exposure and storage
#: are stepped by the error control. (Measured against 20 ns in the README.)
STEPS_PER_ROW = 20


@dataclass
class Frame:
    """Per-subpixel results of one frame (V): ``signal`` = reset level - signal level on
    the column; ``afe`` = the AFE output at the end of its phase 2 (with_afe only)."""
    rows: int
    cols: int
    signal: dict            # kind -> rows x cols array (V)
    reset_level: dict       # kind -> array (V): the column's reset level (before DS)
    afe: dict               # kind -> array (V) or empty
    decks: int
    wall_s: float
    split: str
    failures: list = field(default_factory=list)
    retried: list = field(default_factory=list)   # decks the engine re-ran with looser options

    def as_dict(self) -> dict:
        out = {"rows": self.rows, "cols": self.cols, "split": self.split, "decks": self.decks,
               "wall_s": self.wall_s, "failures": self.failures, "retried": self.retried}
        for k in KINDS:
            out[f"{k}_signal_V"] = _listed(self.signal[k])
            out[f"{k}_reset_level_V"] = _listed(self.reset_level[k])
            if k in self.afe:
                out[f"{k}_afe_out_V"] = _listed(self.afe[k])
        return out


def _listed(a: np.ndarray) -> list:
    """Nested lists with None where a deck failed (JSON has no NaN)."""
    return [[None if v != v else float(v) for v in row] for row in a]


def tiles(rows: int, cols: int, split: str, with_afe: bool = False, kinds=KINDS) -> list[Tile]:
    if split not in SPLITS:
        raise ConfigError("", "split", split, f"one of {', '.join(SPLITS)}")
    if split == "none":
        return [Tile(tuple(kinds), tuple(range(rows)), tuple(range(cols)))]
    lead = (lambda r: (r - 1,) if with_afe and r > 0 else ())
    return [Tile((k,), (r,), tuple(range(cols)), lead(r)) for k in kinds for r in range(rows)]


def _probe(task):
    """Simulate one tile (through the engine and its cache) and read its samples."""
    from ..measure.pixel import levels
    from ..spice import simulate_many
    net, backend, jobs, options, probes = task
    try:
        res = simulate_many([net], backend=backend, jobs=jobs, options=options)[0]
    except SimulationError as exc:
        return {"error": exc.message, "deck": net.title}
    out = {"retried": res.meta["retried"]["reason"] if res.meta.get("retried") else None, "deck": net.title}
    for key, node, timing, row, afe_node in probes:
        sig, rst = levels(res, node, timing, row)
        out[key] = (rst - sig, rst, float(res.at(afe_node, timing.t_reset_level(row))) if afe_node else None)
    return out


def simulate_frame(design, iph_p, iph_s, with_afe: bool = False, split: str = "rows",
                   t_exp: float | None = None, mismatch_seed: int | None = None, backend: str = "batch",
                   jobs: int | None = None, scheduler=None, options=None, max_step: float | None = None,
                   kinds=KINDS) -> Frame:
    """Simulate one frame; see the module docstring for ``split``. ``options``: simulator
    options over the kit's defaults (``spice.options``); ``kinds``: the arrays to simulate
    (the others' results stay NaN)."""
    rows, cols = frame_shape(design, iph_p, iph_s)
    n = design.secondary_per_pixel
    t_exp = design.experiment.t_window if t_exp is None else t_exp
    tm = frame_timings(design, t_exp, rows)
    if max_step is None:
        max_step = min(t.t_row for t in tm.values()) / STEPS_PER_ROW
    tasks = []
    for tile in tiles(rows, cols, split, with_afe, kinds):
        tag = "_".join(PREFIX[k] for k in tile.kinds) + (f"_r{tile.rows[0]}" if len(tile.rows) == 1 else "")
        net = array_bench(design, iph_p, iph_s, tile, t_exp, with_afe, mismatch_seed, max_step,
                          title=f"frame_{rows}x{cols}_{tag}")
        probes = [((k, r, j), f"col_{PREFIX[k]}_{j}", tm[k], r, f"out_col_{PREFIX[k]}_{j}" if with_afe else None)
                  for k in tile.kinds for r in tile.rows for j in tile.columns(k, n)]
        tasks.append((net, backend, 1 if scheduler is not None else jobs, options, probes))
    shape = {"primary": (rows, cols), "secondary": (rows, n * cols)}
    sig = {k: np.full(shape[k], np.nan) for k in KINDS}
    rst = {k: np.full(shape[k], np.nan) for k in KINDS}
    afe = {k: np.full(shape[k], np.nan) for k in KINDS} if with_afe else {}
    failures, retried = [], []
    t0 = time.perf_counter()
    for i, out in run_tasks(_probe, tasks, jobs=jobs, scheduler=scheduler, desc="frame tiles"):
        if "error" in out:
            failures.append({"deck": out["deck"], "message": out["error"]})
            continue
        deck, why = out.pop("deck"), out.pop("retried")
        if why:
            retried.append({"deck": deck, "message": why})
        for (k, r, j), (s, lv, a) in out.items():
            sig[k][r, j], rst[k][r, j] = s, lv
            if with_afe:
                afe[k][r, j] = a
    return Frame(rows, cols, sig, rst, afe, len(tasks), time.perf_counter() - t0, split, failures, retried)
