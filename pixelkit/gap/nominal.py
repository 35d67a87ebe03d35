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
input), interpolated against the signal. Levels are cubic splines of the
charge (linear interpolation left 2 - 3 mV between grid points on the bright,
slewing part). The surrogate's own error is measured against full-chain SPICE
runs at charges between the sweep points and reported with every prediction;
the diagnosis adds it to the measurement noise.

Storage-node (FD-domain) charge does not pass through the PD + FD charge
sharing: three more decks put a known charge on the FD during its hold (a
current pulse, ``circuit_edits.fd_current``) and give, per array, the ratio of
the column's response to FD charge over its response to PD charge (about
(C_PD + C_FD) / C_FD, measured rather than assumed).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scipy.interpolate import CubicSpline

from ..circuits.testbench import dual_pixel_bench, timings
from ..measure.afe import eps, finite_gain_output
from ..measure.pixel import levels
from ..physics.dark import dark_current
from ..physics.subpixel import pd_node
from ..spice import simulate_many

ARRAYS = ("primary", "secondary")
N_GRID = 22
FD_PROBE_Q = {"primary": 2e-15, "secondary": 0.6e-15}   # charge put on FD to measure its response (C)


@dataclass
class Nominal:
    q_grid: dict          # array -> Q grid (C)
    v_sig: dict           # array -> column level at the signal sample (V)
    v_rst: dict           # array -> column reset level (V) at each grid charge
    vref: float
    gain_afe: float       # C11 / C13
    eps_afe: float
    afe_resid: dict      # array -> (signal grid V, residual V) of SPICE over the finite-gain relation
    dark: dict            # array -> (area, perimeter)
    pd: object            # technology photodiode section
    error: dict
    fd_ratio: dict = None  # array -> (Q grid, response to FD charge / response to PD charge)

    def __post_init__(self):
        self._sig = {a: CubicSpline(self.q_grid[a], self.v_sig[a]) for a in ARRAYS}
        self._rst = {a: CubicSpline(self.q_grid[a], self.v_rst[a]) for a in ARRAYS}
        self._res = {a: CubicSpline(*self.afe_resid[a]) for a in ARRAYS}

    def _each(self, arr_idx, x, fns, clip):
        out = np.empty_like(np.asarray(x, float))
        for k, a in enumerate(ARRAYS):
            m = arr_idx == k
            lo, hi = clip[a]
            out[m] = fns[a](np.clip(x[m], lo, hi))
        return out

    def _qclip(self):
        return {a: (self.q_grid[a][0], self.q_grid[a][-1]) for a in ARRAYS}

    def vsig_of(self, arr_idx, q):
        # beyond the grid (the swing's end): the column stays at its last level (saturated)
        return self._each(arr_idx, q, self._sig, self._qclip())

    def vrst_of(self, arr_idx, q=None):
        if q is None:
            return np.where(arr_idx == 0, self.v_rst["primary"].mean(), self.v_rst["secondary"].mean())
        return self._each(arr_idx, q, self._rst, self._qclip())

    def fd_to_pd(self, arr_idx, q):
        """Equivalent PD charge per unit FD charge at PD charge ``q``."""
        out = np.ones_like(q)
        if not self.fd_ratio:
            return out
        for k, a in enumerate(ARRAYS):
            m = arr_idx == k
            out[m] = np.interp(q[m], *self.fd_ratio[a])
        return out

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
        clip = {a: (self.afe_resid[a][0][0], self.afe_resid[a][0][-1]) for a in ARRAYS}
        return out + self._each(arr_idx, signal, self._res, clip)


def _q_max(design, which):
    node = pd_node(design, which, parasitics=True)
    return float(node.charge(design.pixel.v_pd_reset) - node.charge(0.5))


def _fd_deck(design, qp, qs, title):
    """The nominal deck with ``FD_PROBE_Q`` put on every FD during its hold."""
    from .circuit_edits import add_to_subckt, fd_current, specialise
    t_w = design.experiment.t_window
    n = design.secondary_per_pixel
    net = specialise(dual_pixel_bench(design, qp / t_w, qs / t_w, with_afe=True, title=title), n)
    net = add_to_subckt(net, "pix5t_primary", fd_current(design, "primary", FD_PROBE_Q["primary"], "p", "fdcal"))
    for k in range(n):
        net = add_to_subckt(net, f"pix5t_s{k}", fd_current(design, "secondary", FD_PROBE_Q["secondary"], "s",
                                                             "fdcal"))
    return net


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
    pick = [3, 9, 12, 15, 18]
    nets += [dual_pixel_bench(design, mid_p[k] / t_w, mid_s[k] / t_w, with_afe=True, title=f"gapval{k}")
             for k in pick]
    fd_pick = [2, 8, 14]
    nets += [_fd_deck(design, qp[k], qs[k], f"gapfd{k}") for k in fd_pick]
    res = simulate_many(nets, backend=backend)
    sweep, val, fdr = res[:N_GRID], res[N_GRID:N_GRID + len(pick)], res[N_GRID + len(pick):]
    v_sig, v_rst, resid, ratio = {}, {}, {}, {}
    for arr, col, q in (("primary", "col_p", qp), ("secondary", "col_s0", qs)):
        lv = np.array([levels(r, col, tm[arr]) for r in sweep])
        v_sig[arr], v_rst[arr] = lv[:, 0], lv[:, 1]
        out = np.array([float(r.at(f"out_{col}", tm[arr].t_reset_level(0))) for r in sweep])
        sig = lv[:, 1] - lv[:, 0]
        order = np.argsort(sig)
        resid[arr] = (sig[order], (out - finite_gain_output(a.vref, a.c11, a.c13, a.gain, sig))[order])
        slope = CubicSpline(q, lv[:, 0])
        dv = np.array([levels(r, col, tm[arr])[0] for r in fdr]) - lv[fd_pick, 0]
        ratio[arr] = (q[fd_pick], dv / (slope(q[fd_pick], 1) * FD_PROBE_Q[arr]))
    nom = Nominal({"primary": qp, "secondary": qs}, v_sig, v_rst, a.vref, a.c11 / a.c13,
                  eps(a.c11, a.c13, a.gain), resid,
                  {w: (getattr(design, w).area, getattr(design, w).perimeter) for w in ARRAYS},
                  design.tech.photodiode, {}, ratio)
    errs_pix, errs_afe = [], []
    for k, r in zip(pick, val):
        for arr, col, q in (("primary", "col_p", mid_p[k]), ("secondary", "col_s0", mid_s[k])):
            idx = np.array([ARRAYS.index(arr)])
            s_lvl, r_lvl = levels(r, col, tm[arr])
            qq = np.array([q])
            pred = nom.vsig_of(idx, qq)[0]
            errs_pix.append(pred - s_lvl)
            sig = nom.vrst_of(idx, qq) - np.array([pred])
            errs_afe.append(nom.afe(idx, sig)[0] - float(r.at(f"out_{col}", tm[arr].t_reset_level(0))))
    nom.error = {"pixel_max_V": float(np.max(np.abs(errs_pix))), "afe_max_V": float(np.max(np.abs(errs_afe))),
                 "pixel_rms_V": float(np.sqrt(np.mean(np.square(errs_pix)))),
                 "afe_rms_V": float(np.sqrt(np.mean(np.square(errs_afe)))), "n_validation": len(errs_pix),
                 "fd_ratio": {k: [float(x) for x in v[1]] for k, v in ratio.items()}}
    return nom


def features(table, nom: Nominal, design) -> dict:
    """The row quantities the models use, as arrays (with the nominal signal of each row).

    ``J`` is the irradiance at the row's array as a photocurrent density (A/m^2,
    the row's photocurrent over its subpixel's photoactive area): stray-light
    effects scale with it times the exposed area of their structure. ``t_hold``
    is the readout's row time (1 / ``f_read_Hz`` when the data carry it, else the
    design's per-array read rate): how long the AFE holds a sample.
    """
    cols = table.columns
    prev = cols.get("i_ph_prev_A")
    i = table.num("i_ph_A")
    arr = np.array([ARRAYS.index(a) for a in cols["array"]])
    a_pa = np.where(arr == 0, design.primary.photoactive_area, design.secondary.photoactive_area)
    f_design = np.where(arr == 0, design.primary.f_read, design.secondary.f_read)
    f_read = cols.get("f_read_Hz")
    f_read = f_design if f_read is None else np.where(np.isfinite(f_read), f_read, f_design)
    vdd = cols.get("vdd_V")
    vdd = np.full(i.size, design.tech.supply) if vdd is None else np.where(np.isfinite(vdd), vdd, design.tech.supply)
    X = {"arr": arr, "row": table.num("row"), "col": table.num("col"), "i": i,
         "t_int": table.num("t_int_s"), "t_wait": table.num("t_wait_s"), "T": table.num("temp_C"),
         "afe": np.array([p == "afe" for p in cols["probe"]]),
         "i_prev": i.copy() if prev is None else np.where(np.isfinite(prev), prev, i),
         "has_prev": prev is not None,
         "perimeter_ratio": design.secondary.perimeter / design.primary.perimeter,
         "J": i / a_pa, "a_ref": design.primary.photoactive_area,
         "a_sub": np.where(arr == 0, design.primary.area, design.secondary.area),
         "f_read": f_read, "f_design": f_design, "t_hold": 1.0 / f_read,
         "vdd": vdd, "dvdd": vdd - design.tech.supply}
    q = i * X["t_int"] + nom.dark_q(X["arr"], X["T"], X["t_int"])
    X["q"] = q
    X["signal"] = nom.vrst_of(arr, q) - nom.vsig_of(arr, q)
    X["fd_gain"] = nom.fd_to_pd(arr, q)
    return X


def predict(nom: Nominal, X: dict, terms: dict | None = None) -> np.ndarray:
    """Column-level (pixel probe) or AFE-output prediction of each row, with effect ``terms``.

    ``terms`` may hold ``dq`` (extra PD charge, C), ``dq_fd`` (extra charge on the
    storage node FD during its hold, C), ``dv_pix`` (signal shift in the pixel /
    column chain, positive = more signal, V: it pivots at the reset level),
    ``dv_col`` (pixel-probe level shift that double sampling cancels), ``deps``
    (extra AFE gain error), ``dv_afe`` (AFE output shift, V), ``dv_out`` (shift of
    both probes' output stage, V).
    """
    t = terms or {}
    q = X["q"] + t.get("dq", 0.0) + t.get("dq_fd", 0.0) * X["fd_gain"]
    vs = nom.vsig_of(X["arr"], q)
    vr = nom.vrst_of(X["arr"], q)
    signal = vr - vs + t.get("dv_pix", 0.0)
    v_pix = vr - signal + t.get("dv_col", 0.0)
    v_afe = nom.afe(X["arr"], signal, t.get("deps", 0.0)) + t.get("dv_afe", 0.0)
    return np.where(X["afe"], v_afe, v_pix) + t.get("dv_out", 0.0)
