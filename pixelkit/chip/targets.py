"""The 5 % / mid-scale sizing read on a frame with the AFE attached.

The sizing puts the primary at ``experiment.mid_fraction`` of its swing when the
secondary sits at ``experiment.low_fraction`` of its own (the simulation experiment of [Thesis2019], one
dual pixel read through its column without the AFE, finds the photocurrents
``i_mid`` and ``i_5pct``). This reads the same photocurrents in a frame: one dual
column with every column circuit (load, precharge, S1X/S2X, SC AFE), the column
chain of the frame engine, rows

    full, target, dark, target, full

(dark = 0 A, full = the experiment's largest current, target = i_mid / i_5pct), the
same exposure window and no charge compression. A target read after a full row and
after a dark one must give the same fraction of the frame's own swing (full - dark),
on the column's double-sampled signal and at the AFE output: a column that does not
settle reads the first higher than the second.
"""
from __future__ import annotations

import numpy as np

ROWS = ("full", "target", "dark", "target", "full")


def frame_targets(design, exp: dict, backend: str = "batch", jobs=None, options=None) -> dict:
    """Fractions of the frame's swing at the experiment's target currents, per array and probe."""
    from ..experiments.thesis import _i_max
    from .frame import simulate_frame
    n = design.secondary_per_pixel
    level = {"primary": {"full": _i_max(design, "primary"), "target": exp["primary"]["i_mid_A"], "dark": 0.0},
             "secondary": {"full": _i_max(design, "secondary"), "target": exp["secondary"]["i_5pct_A"],
                           "dark": 0.0}}
    ip = np.array([[level["primary"][r]] for r in ROWS])
    is_ = np.array([[level["secondary"][r]] * n for r in ROWS])
    f = simulate_frame(design, ip, is_, with_afe=True, t_exp=design.experiment.t_window, backend=backend,
                       jobs=jobs, options=options)
    want = {"primary": design.experiment.mid_fraction, "secondary": design.experiment.low_fraction}
    out = {"rows": list(ROWS), "failures": f.failures, "arrays": {}}
    for kind in ("primary", "secondary"):
        res = {"target_fraction": want[kind], "current_A": level[kind]["target"]}
        for probe, data, sign in (("column", f.signal[kind][:, 0], 1.0), ("afe", f.afe[kind][:, 0], -1.0)):
            v = sign * data   # the AFE output falls with the signal
            dark, full = v[2], (v[0] + v[4]) / 2
            res[probe] = {"after_full": float((v[1] - dark) / (full - dark)),
                          "after_dark": float((v[3] - dark) / (full - dark)),
                          "swing_V": float(full - dark)}
        out["arrays"][kind] = res
    return out


def worst_departure(t: dict) -> float:
    """Largest |fraction - target fraction| over arrays, probes and rows, relative to the target."""
    worst = 0.0
    for res in t["arrays"].values():
        for probe in ("column", "afe"):
            for k in ("after_full", "after_dark"):
                worst = max(worst, abs(res[probe][k] / res["target_fraction"] - 1))
    return worst
