"""Photo-response non-uniformity from device mismatch: ``experiment.prnu_pixels`` pixels, each on its
own column, in one deck with the Monte Carlo's mismatch on (the model library draws every
instance: each pixel and column its own devices); a dark frame then a frame at
``experiment.lag_fraction`` of the full well. PRNU = sigma / mean of the dark-subtracted signals.
It covers what the devices vary (the follower's gain, FD's junctions and overlaps, the column's
load and S/H switches); the photodiode's own collection and capacitance spread are not drawn (the
behavioural PPD has no mismatch statistics), which docs/pixel4t.md states."""
from __future__ import annotations

import numpy as np

from .run import run


def prnu(design, draw=None, backend: str = "batch") -> dict:
    from ..circuits.cds import cds_bench, timing_of
    from ..measure.cds import cds
    from ..verify.mismatch import Draw, source
    from .signal import current_for, flush_exposure, ladder
    ex = design.experiment
    lad = ladder(design, None, backend)
    tw, t0, n = ex.t_window, flush_exposure(design), ex.prnu_pixels
    i = current_for(design, ex.lag_fraction * lad["fw_est_e"], tw)
    exps = [t0, tw, tw]
    net = cds_bench(design, design.cell(), exps, [[0.0, 0.0, i]] * n, title=f"role_prnu_{n}")
    d = draw or Draw(design.verify.seed, 0, source(design))
    (r,) = run([net], design, d, backend)
    tm, st = timing_of(design), net.meta["frames"]["starts"]
    sig = np.array([cds(r, tm, exps, st, k, 2) - cds(r, tm, exps, st, k, 1) for k in range(n)])
    return {"prnu": float(sig.std(ddof=1) / sig.mean()), "pixels": n, "mean_V": float(sig.mean()),
            "sigma_V": float(sig.std(ddof=1))}
