"""The two model levels of the sizing problem, both in the charge domain.

A subpixel's response is a function of the collected charge Q = I t (the same
charge gives the same signal whatever the window), so each level supplies, per
subpixel, the signal as a fraction of swing against Q:

- ``analytic``: the PD node of ``physics.subpixel`` (PD junction + EC/TG
  diffusions, C(V) exact): f(Q) = drop(Q) / swing, drop from the reset level,
  swing the design's ``pixel.swing``.
- ``spice``: the double-sampled column signal of the generated pixel measured
  by the thesis [Thesis2019] experiment (``experiments.thesis``): f(Q) = (signal - dark) /
  swing at Q = I t_window. This carries the SF gain and offset, FD charge
  sharing, C(V) and the real sampling chain.

Each is returned as sampled curves (Q grid, fraction) that casadi turns into
interpolants.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..physics.subpixel import pd_node


@dataclass(frozen=True)
class Curves:
    level: str
    q_primary: np.ndarray      # C
    f_primary: np.ndarray      # fraction of swing
    q_secondary: np.ndarray
    f_secondary: np.ndarray
    q_full_secondary: float    # charge at the full swing of the secondary (dark-current budget)

    def charge_at(self, which: str, frac: float) -> float:
        q, f = (self.q_primary, self.f_primary) if which == "primary" else (self.q_secondary, self.f_secondary)
        f = np.maximum.accumulate(f)
        if not f[0] <= frac <= f[-1]:
            raise ValueError(f"{frac:.3g} of swing is outside the {self.level} curve of the {which} subpixel")
        return float(np.interp(frac, f, q))


def analytic_curves(design, n: int = 200) -> Curves:
    swing, v0 = design.pixel.swing, design.pixel.v_pd_reset
    out = {}
    for which in ("primary", "secondary"):
        node = pd_node(design, which, parasitics=True)
        drop = np.linspace(0.0, swing, n)
        q = node.charge(v0) - node.charge(v0 - drop)
        out[which] = (np.asarray(q, float), drop / swing)
    return Curves("analytic", *out["primary"], *out["secondary"], float(out["secondary"][0][-1]))


def spice_curves(design, experiment: dict) -> Curves:
    t_w = experiment["t_window_s"]
    out = {}
    for which in ("primary", "secondary"):
        e = experiment[which]
        order = np.argsort(e["sweep_A"])
        q = np.asarray(e["sweep_A"])[order] * t_w
        f = (np.asarray(e["signal_V"])[order] - e["pedestal_V"]) / e["swing_V"]
        out[which] = (q, f)
    full = analytic_curves(design).q_full_secondary
    return Curves("spice", *out["primary"], *out["secondary"], full)
