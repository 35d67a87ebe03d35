"""Nominal prediction of measured rows: a SPICE-calibrated surrogate, with its own error.

The nominal pixel responds to the charge it collects, Q = (i_ph + I_dark(T)) t_int
(the design's dark current, technology law), so one SPICE sweep of the full chain
(dual pixel + column loads + S1X/S2X + SC AFE, both arrays in each deck, the
experiment's window) over Q gives, per array, the column level at the signal
sample V_sig(Q) and at the reset sample V_rst, as the column really is: loaded by
the AFE's C11, so bright signals that cannot slew within the sampling window are
compressed exactly as on the chip. The AFE probe follows the finite-gain SC
relation of ``measure.afe`` applied to those sampled levels, plus the residual
SPICE shows on the sweep (switch injection, incomplete settling of the AFE
input), interpolated against the signal. The surrogate's own error is
measured against full-chain SPICE runs at charges between the sweep points and
reported with every prediction.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..circuits.testbench import dual_pixel_bench, timings
from ..measure.afe import eps, finite_gain_output
from ..measure.pixel import levels
from ..physics.dark import dark_current
from ..physics.subpixel import pd_node
from ..spice import simulate_many

ARRAYS = ("primary", "secondary")
N_GRID = 14


@dataclass
class Nominal:
    q_grid: dict          # array -> Q grid (C)
    v_sig: dict           # array -> column level at the signal sample (V)
    v_rst: dict           # array -> column reset level (V)
    vref: float
    gain_afe: float       # C11 / C13
    eps_afe: float
    afe_resid: dict      # array -> (signal grid V, residual V) of SPICE over the finite-gain relation
    dark: dict            # array -> (area, perimeter)
    pd: object            # technology photodiode section
    error: dict

    def vsig_of(self, arr_idx, q):
        out = np.empty_like(q)
        for k, a in enumerate(ARRAYS):
            m = arr_idx == k
            out[m] = np.interp(q[m], self.q_grid[a], self.v_sig[a])
        return out

    def vrst_of(self, arr_idx):
        return np.where(arr_idx == 0, self.v_rst["primary"], self.v_rst["secondary"])

    def dark_q(self, arr_idx, temp_C, t_int):
        out = np.empty_like(t_int)
        for k, a in enumerate(ARRAYS):
            m = arr_idx == k
            area, per = self.dark[a]
            out[m] = dark_current(area, per, temp_C[m] + 273.15, self.pd) * t_int[m]
        return out

    def afe(self, arr_idx, signal, eps_extra=0.0):
        e = self.eps_afe + eps_extra
        out = self.vref - self.gain_afe * signal / (1 + e)
        for k, a in enumerate(ARRAYS):
            m = arr_idx == k
            out[m] += np.interp(signal[m], *self.afe_resid[a])
        return out


def _q_max(design, which):
    node = pd_node(design, which, parasitics=True)
    return float(node.charge(design.pixel.v_pd_reset) - node.charge(0.5))


def build_nominal(design, backend: str = "batch") -> Nominal:
    t_w = design.experiment.t_window
    tm = timings(design, t_w)
    u = np.linspace(0.0, 1.0, N_GRID) ** 1.5
    qp, qs = u * _q_max(design, "primary"), u * _q_max(design, "secondary")
    nets = [dual_pixel_bench(design, a / t_w, b / t_w, with_afe=True, title=f"gapnom{k}")
            for k, (a, b) in enumerate(zip(qp, qs))]
    a = design.afe
    # validation: full chain at charges between the grid points
    mid_p, mid_s = (qp[1:] + qp[:-1]) / 2, (qs[1:] + qs[:-1]) / 2
    pick = [2, 6, 10]
    nets += [dual_pixel_bench(design, mid_p[k] / t_w, mid_s[k] / t_w, with_afe=True, title=f"gapval{k}")
             for k in pick]
    res = simulate_many(nets, backend=backend)
    sweep, val = res[:N_GRID], res[N_GRID:]
    v_sig, v_rst, resid = {}, {}, {}
    for arr, col, q in (("primary", "col_p", qp), ("secondary", "col_s0", qs)):
        lv = np.array([levels(r, col, tm[arr]) for r in sweep])
        v_sig[arr], v_rst[arr] = lv[:, 0], float(np.mean(lv[:, 1]))
        out = np.array([float(r.at(f"out_{col}", tm[arr].t_reset_level(0))) for r in sweep])
        sig = v_rst[arr] - lv[:, 0]
        order = np.argsort(sig)
        resid[arr] = (sig[order], (out - finite_gain_output(a.vref, a.c11, a.c13, a.gain, sig))[order])
    nom = Nominal({"primary": qp, "secondary": qs}, v_sig, v_rst, a.vref, a.c11 / a.c13,
                  eps(a.c11, a.c13, a.gain), resid,
                  {w: (getattr(design, w).area, getattr(design, w).perimeter) for w in ARRAYS},
                  design.tech.photodiode, {})
    errs_pix, errs_afe = [], []
    for k, r in zip(pick, val):
        for arr, col, q in (("primary", "col_p", mid_p[k]), ("secondary", "col_s0", mid_s[k])):
            idx = np.array([ARRAYS.index(arr)])
            s_lvl, r_lvl = levels(r, col, tm[arr])
            pred = nom.vsig_of(idx, np.array([q]))[0]
            errs_pix.append(pred - s_lvl)
            sig = nom.vrst_of(idx) - np.array([pred])
            errs_afe.append(nom.afe(idx, sig)[0] - float(r.at(f"out_{col}", tm[arr].t_reset_level(0))))
    nom.error = {"pixel_max_V": float(np.max(np.abs(errs_pix))), "afe_max_V": float(np.max(np.abs(errs_afe))),
                 "pixel_rms_V": float(np.sqrt(np.mean(np.square(errs_pix)))),
                 "afe_rms_V": float(np.sqrt(np.mean(np.square(errs_afe)))), "n_validation": len(errs_pix)}
    return nom


def features(table, nom: Nominal, design) -> dict:
    """The row quantities the models use, as arrays (with the nominal signal of each row)."""
    prev = table.columns.get("i_ph_prev_A")
    i = table.num("i_ph_A")
    X = {"arr": np.array([ARRAYS.index(a) for a in table.columns["array"]]),
         "row": table.num("row"), "col": table.num("col"), "i": i,
         "t_int": table.num("t_int_s"), "t_wait": table.num("t_wait_s"), "T": table.num("temp_C"),
         "afe": np.array([p == "afe" for p in table.columns["probe"]]),
         "i_prev": i.copy() if prev is None else np.where(np.isfinite(prev), prev, i),
         "perimeter_ratio": design.secondary.perimeter / design.primary.perimeter,
         "c_m": design.secondary.area / design.secondary.photoactive_area}
    q = i * X["t_int"] + nom.dark_q(X["arr"], X["T"], X["t_int"])
    X["signal"] = nom.vrst_of(X["arr"]) - nom.vsig_of(X["arr"], q)
    return X


def predict(nom: Nominal, X: dict, terms: dict | None = None) -> np.ndarray:
    """Column-level (pixel probe) or AFE-output prediction of each row, with effect ``terms``.

    ``terms`` may hold ``dq`` (extra charge, C), ``dv_pix`` (pixel-level signal shift,
    positive = more signal, V), ``deps`` (extra AFE gain error), ``dv_afe`` (AFE output shift, V).
    """
    t = terms or {}
    q = X["i"] * X["t_int"] + nom.dark_q(X["arr"], X["T"], X["t_int"]) + t.get("dq", 0.0)
    vs = nom.vsig_of(X["arr"], q)
    vr = nom.vrst_of(X["arr"])
    signal = vr - vs + t.get("dv_pix", 0.0)
    v_pix = vr - signal
    v_afe = nom.afe(X["arr"], signal, t.get("deps", 0.0)) + t.get("dv_afe", 0.0)
    return np.where(X["afe"], v_afe, v_pix)
