"""The pixel's transfer measured in SPICE: the camera's response.

The dual-pixel bench of the simulation experiment (both arrays exposed over
``experiment.t_window``, read with the global-shutter sequence), at ``POINTS`` photocurrents
from dark to the current that takes the PD node through the design swing; per array, the
double-sampled column signal above the pedestal against the collected charge I t_window.
Denser than the experiment's sweep (9 + 6 points), because the camera's saturation (EMVA's
variance maximum) sits in the knee where the column compresses towards ground; the runs
are cached like every deck.
"""
from __future__ import annotations

import numpy as np

from ..circuits.testbench import timings
from ..constants import Q
from ..measure.pixel import double_sampled

POINTS = 33


def spice_transfer(design, backend: str = "batch", jobs: int | None = None) -> dict:
    """{array: {"electrons": (...), "signal_V": (...), "swing_V": float}} (signal above the pedestal)."""
    from ..experiments.thesis import _i_max, sweep
    t_w = design.experiment.t_window
    ip = np.linspace(0.0, _i_max(design, "primary"), POINTS)
    is_ = np.linspace(0.0, _i_max(design, "secondary"), POINTS)
    runs = sweep(design, ip, is_, backend, jobs, "transfer")
    tm = timings(design, t_w)
    out = {}
    for which, col, cur in (("primary", "col_p", ip), ("secondary", "col_s0", is_)):
        s = np.array([double_sampled(r, col, tm[which]) for r in runs])
        s = np.maximum(s - s[0], 0.0)
        out[which] = {"electrons": tuple((cur * t_w / Q).tolist()), "signal_V": tuple(s.tolist()),
                      "swing_V": float(s.max())}
    return out
