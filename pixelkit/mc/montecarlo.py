"""Monte Carlo mismatch of an array frame, turned into fixed-pattern figures.

One seed = one chip: every MOSFET of the array, its column loads, samplers and AFEs
draws its threshold and current factor from the model library's own statistics
(``sw_stat_mismatch = 1``, ngspice ``.options seed``), once: the frame is one deck, so a
column's load, samplers and AFE are the same devices for all its rows (a split frame
would draw them again in every deck and blur column FPN into pixel FPN); every AFE capacitor from
the technology's capacitor matching. The same chip is simulated dark and under a
uniform flat field (50 % of the primary's full scale), and per array:

- ``pedestal_V``: mean dark double-sampled signal (switch charge injection and
  feedthrough: the signal of no light), ``dsnu_V`` its pixel-to-pixel sigma;
- ``prnu_pct``: sigma / mean of the light response (flat - dark);
- ``column_fpn_V``: sigma of the column means of the dark signal (at the AFE output
  when the AFE is simulated, else on the column);
- ``offset_fpn_V``: sigma of the column's reset level within columns (the offset FPN
  before double sampling, which DS removes), checked against the Pelgrom estimate
  of ``pelgrom.reset_offset_sigma``;
- secondary: ``target_over_dsnu``: the 5 % target signal over the dark-signal sigma
  (how many sigmas of pedestal spread separate the target from no light).

Reproducible: the same seed gives the same draws (ngspice's seed and numpy's
``default_rng([seed, ...])``), independent of the cache and of the worker count.
"""
from __future__ import annotations

import numpy as np

from ..chip.frame import simulate_frame
from ..chip.scene import default_map, photocurrents
from .pelgrom import reset_offset_sigma


def _within_column_sigma(levels: np.ndarray) -> float:
    """Pooled sigma of ``levels`` (rows x columns) after removing each column's mean."""
    r = levels - levels.mean(axis=0, keepdims=True)
    dof = levels.size - levels.shape[1]
    return float(np.sqrt((r ** 2).sum() / dof))


def run_monte_carlo(design, rows: int, cols: int, seed: int, with_afe: bool = False, backend: str = "batch",
                    jobs=None, scheduler=None, options=None, max_step: float | None = None) -> dict:
    """The figures above for one chip (``seed``) of ``rows`` x ``cols`` dual pixels. ``options`` (ngspice
    options, e.g. ``{"reltol": 1e-6}``) and ``max_step`` go to both frames' decks (default: the frame's)."""
    n = design.secondary_per_pixel
    dark = np.zeros((rows, cols)), np.zeros((rows, n * cols))
    m, unit = default_map(rows, n * cols, "uniform")
    ph = photocurrents(design, rows, cols, m, unit)
    kw = dict(with_afe=with_afe, mismatch_seed=seed, split="none", backend=backend, jobs=jobs, scheduler=scheduler,
              options=options, max_step=max_step)
    fd = simulate_frame(design, *dark, **kw)
    fl = simulate_frame(design, ph.iph_p, ph.iph_s, **kw)
    out = {"seed": seed, "rows": rows, "cols": cols, "with_afe": with_afe, "corner": design.corner_name,
           "failures": fd.failures + fl.failures}
    for k in ("primary", "secondary"):
        d_sig, l_sig = fd.signal[k], fl.signal[k]
        resp = l_sig - d_sig
        col_src = fd.afe[k] if with_afe else d_sig
        out[k] = {"pedestal_V": float(d_sig.mean()), "dsnu_V": float(d_sig.std(ddof=1)),
                  "prnu_pct": float(100 * resp.std(ddof=1) / resp.mean()),
                  "column_fpn_V": float(col_src.mean(axis=0).std(ddof=1)) if col_src.shape[1] > 1 else float("nan"),
                  "offset_fpn_V": _within_column_sigma(fd.reset_level[k]),
                  "dark_signal_V": d_sig.tolist(), "reset_level_V": fd.reset_level[k].tolist()}
        if with_afe:
            gain = (fl.afe[k] - fd.afe[k]) / resp
            out[k]["afe_gain_fpn_pct"] = float(100 * np.abs(gain.mean(axis=0)).std(ddof=1) / np.abs(gain).mean())
    target = design.experiment.low_fraction * design.pixel.swing
    out["secondary"]["target_over_dsnu"] = target / out["secondary"]["dsnu_V"]
    est = reset_offset_sigma(design, backend=backend)
    both = np.concatenate([fd.reset_level[k] for k in ("primary", "secondary")], axis=1)  # same SF size
    measured = _within_column_sigma(both)
    out["pelgrom"] = {**est, "measured_offset_fpn_V": measured, "ratio": measured / est["sigma_reset_V"],
                      "samples": int(both.size), "dof": int(both.size - both.shape[1])}
    return out
