"""The ratio pixel's experiment: loop transfer, counter law, resolution, bias limits.

Two decks (one per bias, ``readout.i_bias`` and ``readout.i_bias_high``) with the
same five pixels and the same photocurrents (the same scene):

- ratio sweep R_F = 1, 1.618, 3, 10, 20, 30 (signs mixed over the horizontal and
  vertical pairs) with the pair's total photocurrent equal to the nominal bias
  (the paper's operating point: all four loop devices near 10 nA);
- intensity sweep at R_F = ``experiment.ratio_intensity`` with the pair total at
  0.03, 0.3, 3 and 10 times the nominal bias.

Measured: the output-current ratio during precharge (the loop's DC transfer,
against the photocurrent ratio); the inverter trip times (tau calibrated from the
uniform pair, t = 2 tau; the interval of every other pair against
tau (R_F - 1/R_F)); the counter and the decoder on those intervals.
"""
from __future__ import annotations

import time

import numpy as np

from ...errors import PixelkitError
from ...progress import step
from ...spice import simulate_many
from .circuit import T_PRE, ratio_bench, tau_nominal
from .devices import weak_inversion
from .law import counter, interval_over_tau, ratio_from_count, ratio_from_interval, resolution

RATIOS = (1.0, 1.618, 3.0, 10.0, 20.0, 30.0)
INTENSITIES = (0.03, 0.3, 1.0, 3.0, 10.0)


def _pair(rf: float, total: float) -> tuple:
    m = total / (1.0 + rf)
    return (rf * m, m)


def cells(design) -> list[dict]:
    """Every (pixel, direction) cell of the bench: its photocurrents, ratio and role."""
    ib, r = design.readout.i_bias, design.experiment.ratio_intensity
    out = []
    for k, rf in enumerate(RATIOS):
        signed = rf if k % 2 == 0 else 1.0 / rf
        out.append({"role": "ratio", "rf": signed, "total_A": ib, "i": _pair(signed, ib)})
    for k, s in enumerate(x for x in INTENSITIES if x != 1.0):
        signed = r if k % 2 == 0 else 1.0 / r
        out.append({"role": "intensity", "rf": signed, "total_A": s * ib, "i": _pair(signed, s * ib)})
    return out


def bench_pairs(cs):
    return [(cs[2 * k]["i"], cs[2 * k + 1]["i"]) for k in range(len(cs) // 2)]


def _trip(t, v, level):
    k = np.nonzero((v[:-1] < level) & (v[1:] >= level))[0]
    if not len(k):
        return float("nan")
    k = k[0]
    return float(t[k] + (level - v[k]) * (t[k + 1] - t[k]) / (v[k + 1] - v[k])) - T_PRE


def measure(design, result, cs) -> list[dict]:
    vdd = design.tech.supply
    rows = []
    for n, c in enumerate(cs):
        k, d = n // 2, "hv"[n % 2]
        i_p = float(result.at(f"i(v.xc_{d}_p{k}.va)", T_PRE * 0.95))
        i_m = float(result.at(f"i(v.xc_{d}_m{k}.va)", T_PRE * 0.95))
        t_p = _trip(result.time, result[f"v(out_{d}_p{k})"], vdd / 2)
        t_m = _trip(result.time, result[f"v(out_{d}_m{k})"], vdd / 2)
        if np.isnan(t_p) or np.isnan(t_m):
            raise PixelkitError(f"{design.source}: pixel {k} ({d} pair, R_F = {c['rf']:.3g}) did not trip within "
                                f"{result.time[-1] * 1e6:.3g} us: check readout.c_par, v_clamp_gate and v_select")
        rows.append({**{x: c[x] for x in ("role", "rf", "total_A")}, "pixel": k, "pair": d,
                     "i_out_p_A": i_p, "i_out_m_A": i_m, "out_ratio": i_m / i_p,
                     "ratio_err_frac": (i_m / i_p) / c["rf"] - 1.0, "t_p_s": t_p, "t_m_s": t_m,
                     "interval_s": t_p - t_m})
    return rows


def _readout(design, rows, tau):
    """Counter + decoder on the measured intervals; the interval law against tau."""
    ro = design.readout
    t_lsb = ro.lsb_per_tau * tau
    worst = 0.0
    for r in rows:
        x = r["interval_s"] / tau
        r["interval_over_tau"] = x
        r["law_over_tau"] = interval_over_tau(r["rf"])
        r["count"] = counter(r["interval_s"], t_lsb, ro.counter_bits)
        r["rf_decoded_count"] = ratio_from_count(r["count"], t_lsb, tau)
        r["rf_decoded_interval"] = ratio_from_interval(x)
        if r["role"] == "ratio" and abs(r["law_over_tau"]) > 0.5:
            r["law_err_frac"] = x / r["law_over_tau"] - 1.0
            worst = max(worst, abs(r["law_err_frac"]))
    return worst


def _rf_min_spice(rows, lsb_per_tau):
    """The ratio whose measured interval is one T_LSB (interpolated in ln R_F)."""
    pts = sorted((max(r["rf"], 1 / r["rf"]), abs(r["interval_over_tau"])) for r in rows if r["role"] == "ratio")
    rf, x = np.array(pts).T
    return float(np.exp(np.interp(lsb_per_tau, x, np.log(rf))))


def _spread(rows, rf):
    """Relative spread of the output ratio over the intensity sweep (all at ratio ``rf``)."""
    r0 = [r for r in rows if r["role"] == "intensity" or (r["role"] == "ratio" and
                                                         abs(max(r["rf"], 1 / r["rf"]) - rf) < 1e-9)]
    got = np.array([max(r["out_ratio"], 1 / r["out_ratio"]) for r in r0])
    return float((got.max() - got.min()) / rf), [{"total_A": r["total_A"], "err_frac": abs(r["ratio_err_frac"])}
                                                   for r in sorted(r0, key=lambda q: q["total_A"])]


def run_ratio_experiment(design, backend: str = "batch", jobs: int | None = None) -> dict:
    t0 = time.perf_counter()
    ro = design.readout
    cs = cells(design)
    biases = (ro.i_bias, ro.i_bias_high)
    nets = [ratio_bench(design, bench_pairs(cs), ib, title=f"ratio_bench_{k}") for k, ib in enumerate(biases)]
    with step(f"ratio pixel: {len(nets)} benches"):
        results = simulate_many(nets, backend=backend, jobs=jobs)
    out = {"design": design.name, "family": "ratio", "backend": backend}
    per_bias = []
    for ib, res in zip(biases, results):
        rows = measure(design, res, cs)
        uniform = next(r for r in rows if r["role"] == "ratio" and r["rf"] == 1.0)
        tau = 0.5 * (uniform["t_p_s"] + uniform["t_m_s"]) / 2.0
        law_err = _readout(design, rows, tau)
        ratio_rows = [r for r in rows if r["role"] == "ratio"]
        spread, by_level = _spread(rows, design.experiment.ratio_intensity)
        per_bias.append({"i_bias_A": ib, "tau_s": tau, "tau_nominal_s": tau_nominal(design, ib),
                         "ratio_law_max_err_frac": max(abs(r["ratio_err_frac"]) for r in ratio_rows),
                         "interval_law_max_err_frac": law_err,
                         "rf_min_spice": _rf_min_spice(rows, ro.lsb_per_tau),
                         "intensity_spread_frac": spread, "intensity_sweep": by_level, "cells": rows})
    nom, high = per_bias
    res_ = resolution(ro.lsb_per_tau, ro.counter_bits)
    out.update({
        "i_bias_A": ro.i_bias,
        "ratio_law_max_err_frac": nom["ratio_law_max_err_frac"],
        "interval_law_max_err_frac": nom["interval_law_max_err_frac"],
        "tau_s": nom["tau_s"],
        "rf_min": res_["rf_min"], "rf_max": res_["rf_max"], "dr_adj_db": res_["dr_adj_db"],
        "rf_min_spice": nom["rf_min_spice"],
        "counter_bits": ro.counter_bits, "lsb_per_tau": ro.lsb_per_tau,
        "high_bias": {k: high[k] for k in ("i_bias_A", "ratio_law_max_err_frac", "interval_law_max_err_frac",
                                           "intensity_spread_frac", "tau_s")},
        "intensity_spread_frac": nom["intensity_spread_frac"],
        "weak_inversion": weak_inversion(design, backend=backend),
        "biases": per_bias,
        "n_runs": len(results),
        "n_cached": sum(bool(r.meta.get("cached")) for r in results),
        "wall_s": time.perf_counter() - t0,
    })
    return out
