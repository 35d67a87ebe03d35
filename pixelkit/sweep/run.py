"""Run a sweep: every point of the axes' grid through the engine, measured, labelled.

Each point is the dual-pixel bench (optionally with the AFEs) at the point's design,
stimulus and simulator options; it is measured where it ran and only its figures come
back: the double-sampled column signals (``signal_primary_V``, ``signal_secondary_V``),
the column reset levels, and with the AFE its outputs. The result is an
``xarray.Dataset`` over the axes plus ``ok``/``message``/``cached`` per point, and a
tidy table (one row per point, units in the column names).

Resume: a point's simulation is stored in the content-hash cache as soon as it
finishes, so re-running an interrupted sweep recomputes only the points that had not
finished (their rows say ``cached = False``, the others ``True``). A point that fails
(after the engine's retry) is kept with ngspice's message; it is never dropped.
"""
from __future__ import annotations

import itertools
import time
from dataclasses import dataclass

import numpy as np

from ..errors import SimulationError
from ..chip.scene import default_stimulus
from ..spice.executors import run_tasks
from .space import Axis, design_with, si_value

FIGURES = ("signal_primary_V", "signal_secondary_V", "reset_primary_V", "reset_secondary_V")
AFE_FIGURES = ("afe_primary_V", "afe_secondary_V")


@dataclass
class Sweep:
    axes: list
    points: list        # dicts: axis values + figures (None where failed) + ok/message/cached
    wall_s: float
    dataset: object     # xarray.Dataset

    @property
    def failures(self) -> list:
        return [p for p in self.points if not p["ok"]]

    def table(self) -> str:
        """CSV text, one row per point (units in the column names)."""
        cols = [a.column for a in self.axes] + [c for c in self.points[0] if c not in {a.name for a in self.axes}]
        lines = [",".join(cols)]
        for p in self.points:
            row = {**{a.column: p[a.name] for a in self.axes}, **p}
            lines.append(",".join(_cell(row[c]) for c in cols))
        return "\n".join(lines) + "\n"


def _cell(v) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return "" if v != v else f"{v:.9g}"
    s = str(v)
    return '"' + s.replace('"', '""') + '"' if any(ch in s for ch in ',"\n') else s


def _point(task):
    """One point: simulate (through the cache) and measure. Runs in a worker."""
    from ..circuits.testbench import dual_pixel_bench, timings
    from ..measure.pixel import levels
    from ..spice import simulate_many
    design, stim, options, with_afe, backend, jobs, title = task
    net = dual_pixel_bench(design, stim["iph_p"], stim["iph_s"], stim["t_exp"], with_afe=with_afe, title=title)
    try:
        # shared backend: the engine's process pool of ``jobs`` workers serves every thread
        res = simulate_many([net], backend=backend, jobs=jobs, options=options or None)[0]
    except SimulationError as exc:
        return {"ok": False, "message": exc.message, "cached": False}
    tm = timings(design, stim["t_exp"])
    out = {"ok": True, "message": "retried: " + res.meta["retried"]["reason"] if res.meta.get("retried") else "",
           "cached": bool(res.meta.get("cached"))}
    for kind, node in (("primary", "col_p"), ("secondary", "col_s0")):
        sig, rst = levels(res, node, tm[kind])
        out[f"signal_{kind}_V"], out[f"reset_{kind}_V"] = rst - sig, rst
        if with_afe:
            out[f"afe_{kind}_V"] = float(res.at(f"out_{node}", tm[kind].t_reset_level(0)))
    return out


def run_sweep(design, axes: list[Axis], with_afe: bool = False, backend: str = "batch", jobs=None,
              scheduler=None) -> Sweep:
    """Every point of the grid of ``axes`` (outer product, first axis slowest)."""
    names = [a.name for a in axes]
    if len(set(names)) != len(names):
        from ..errors import ConfigError
        raise ConfigError("sweep", "--over", names, "each axis once")
    grid = list(itertools.product(*(a.values for a in axes)))
    designs, si = {}, []
    tasks = []
    for k, combo in enumerate(grid):
        vals = dict(zip(names, combo))
        dkey = tuple((a.name, vals[a.name]) for a in axes if a.kind == "design")
        if dkey not in designs:
            designs[dkey] = design_with(design, dict(dkey))
        d = designs[dkey]
        si.append({f"{name}_{unit}" if unit else f"{name}_si": v for name, _ in dkey
                   for v, unit in [si_value(d, name) or (None, None)] if v is not None})
        stim = default_stimulus(d, vals.get("t_exp", d.experiment.t_window))
        stim.update({a.name: vals[a.name] for a in axes if a.kind == "stimulus"})
        opts = tuple((a.name.split(".", 1)[1], vals[a.name]) for a in axes if a.kind == "option")
        tasks.append((d, stim, opts, with_afe, backend, 1 if scheduler is not None else jobs, f"sweep{k}"))
    t0 = time.perf_counter()
    outs = [None] * len(tasks)
    for i, out in run_tasks(_point, tasks, jobs=jobs, scheduler=scheduler, desc="sweep points"):
        outs[i] = out
    figs = FIGURES + (AFE_FIGURES if with_afe else ())
    points = [{**dict(zip(names, combo)), **extra, **{f: out.get(f) for f in figs},
               "ok": out["ok"], "message": out["message"], "cached": out["cached"]}
              for combo, extra, out in zip(grid, si, outs)]
    return Sweep(list(axes), points, time.perf_counter() - t0, _dataset(axes, points, figs))


def _dataset(axes, points, figs):
    """The points as an xarray Dataset over the axes (coordinates as given)."""
    import xarray as xr
    shape = tuple(len(a.values) for a in axes)
    coords = {a.name: list(a.values) for a in axes}
    data = {}
    for f in (*figs, "ok", "message", "cached"):
        if f in figs:
            arr = np.array([np.nan if p[f] is None else p[f] for p in points], float).reshape(shape)
        else:
            arr = np.array([p[f] for p in points], dtype=object if f == "message" else bool).reshape(shape)
        data[f] = ([a.name for a in axes], arr)
    ds = xr.Dataset(data, coords=coords)
    for f in figs:
        ds[f].attrs["units"] = "V"
    for a in axes:
        if a.kind == "stimulus":
            ds[a.name].attrs["units"] = a.column.rsplit("_", 1)[1]
        for key in [k for k in points[0] if k.startswith(a.name + "_") and a.kind == "design"]:
            si = {p[a.name]: p[key] for p in points}
            ds = ds.assign_coords({key: (a.name, [si[v] for v in a.values])})
    return ds
