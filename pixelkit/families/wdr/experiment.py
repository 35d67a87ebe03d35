"""The WDR pixel's experiment: decoded intensity over > 5 decades, knee, DR.

One deck: a dark pixel plus photocurrents from 1e-3 of the knee to a flip at
1.3 T (all pixels share the coding buses and the controls). The truth is the
photocurrent each pixel's current source carries; the decoder only sees the
stored voltages (C1, C2, V(int) at the end of the frame) and each pixel's reset
sample, plus the dark pixel read at half and full exposure (its dark current and
how that falls with the node voltage).

- decode_max_err_frac: worst |I_decoded / I_true - 1| over the sweep
- knee: the smallest current that flipped and the largest that did not bracket
  the model's knee (the photocurrent that, with the dark current, takes the node
  from V_start to V0 in 2^N T: ``decode.knee_current``); a second deck moves V0 halfway
  to the reset level and puts two pixels at 0.9x and 1.1x the new model knee:
  only the brighter may flip (the knee follows V0 as the model says)
- dr_db: 20 log10(I_max / I_min), I_max from SPICE (the current that would flip at
  T, scaled from the brightest pixel's decoded t_c), I_min from the node's
  noise floor; compared with CVDR + 20 log10(2^N) and the paper's 112 / ~100 dB
"""
from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np

from ...progress import step
from ...spice import simulate_many
from .circuit import T_RESET, t_exposure, wdr_bench
from .dark import dark_current_vs_voltage
from .decode import dark_model, decode, knee_current
from .model import delta_q, figures

LOW = (1e-3, 1e-2, 0.3, 0.85)           # fractions of the knee current (signal 3)
HIGH_TC = (220.0, 30.0, 6.0, 1.3)   # flip times in units of T (comparator)
KNEE_BRACKET = (0.9, 1.1)           # around the model's knee at a second V0


def currents(design) -> list[float]:
    m = figures(design)
    dq = m["i_knee_A"] * t_exposure(design)
    return [0.0, *(f * m["i_knee_A"] for f in LOW), *(dq / (k * design.coding.t_unit) for k in HIGH_TC)]


def _other_v0(design):
    """The design with V0 halfway between the reference V0 and the reset level."""
    px = design.pixel
    return replace(design, pixel=replace(px, v0=(px.v0 + px.v_reset) / 2))


def _flipped(design, result, k) -> bool:
    """Did pixel ``k``'s comparator act (its read-in switches opened)?"""
    return bool(np.any(result[f"v(xp{k}.samp)"] > design.tech.supply / 2))


def run_wdr_experiment(design, backend: str = "batch", jobs: int | None = None) -> dict:
    t0 = time.perf_counter()
    cd = design.coding
    cur = currents(design)
    with step(f"WDR pixel: {len(cur)} pixels over 2^{cd.steps} T"):
        res = simulate_many([wdr_bench(design, cur)], backend=backend, jobs=jobs)[0]
    t_exp = t_exposure(design)
    t_read = res.time[-1]
    t_rs = T_RESET + 1e-6
    v_start = [float(res.at(f"v(out_s3_{k})", t_rs)) for k in range(len(cur))]
    v3 = [float(res.at(f"v(out_s3_{k})", t_read)) for k in range(len(cur))]
    v_half = float(res.at("v(out_s3_0)", T_RESET + t_exp / 2))
    dark = dark_model(design, v_start[0], v_half, v3[0])
    i_dark = float(delta_q(design, v_start[0], v3[0])) / t_exp
    rows = []
    for k, i in enumerate(cur[1:], start=1):
        v1, v2 = float(res.at(f"v(out_s1_{k})", t_read)), float(res.at(f"v(out_s2_{k})", t_read))
        d = decode(design, v1, v2, v3[k], v_start[k], dark)
        samp = res[f"v(xp{k}.samp)"]
        hit = np.nonzero(samp > design.tech.supply / 2)[0]
        t_flip = float(res.time[hit[0]]) - T_RESET - cd.t_delay if len(hit) else None
        rows.append({"i_true_A": i, "i_decoded_A": d["i_A"], "err_frac": d["i_A"] / i - 1.0,
                     "regime": d["regime"], "t_c_decoded_s": d["t_c_s"], "t_c_spice_s": t_flip,
                     "v1_V": v1, "v2_V": v2, "v3_V": v3[k], "v_start_V": v_start[k]})
    m = figures(design, v_start=float(np.mean(v_start)))
    knee = knee_current(design, float(np.mean(v_start)), dark)
    alt = _other_v0(design)
    alt_knee = knee_current(alt, float(np.mean(v_start)), dark)
    alt_cur = [f * alt_knee for f in KNEE_BRACKET]
    with step("WDR pixel: the knee at a second V0"):
        res_alt = simulate_many([wdr_bench(alt, alt_cur, title="wdr_bench_v0")], backend=backend, jobs=jobs)[0]
    bright = rows[-1]
    i_max_sim = bright["i_true_A"] * bright["t_c_decoded_s"] / cd.t_unit
    flipped = [r["i_true_A"] for r in rows if r["regime"] == "high"]
    held = [r["i_true_A"] for r in rows if r["regime"] == "low"]
    dr = 20 * math.log10(i_max_sim / m["i_min_A"])
    return {
        "design": design.name, "family": "wdr", "backend": backend,
        "decode_max_err_frac": max(abs(r["err_frac"]) for r in rows),
        "decode_max_err_frac_one_dark_rate": max(
            abs(decode(design, r["v1_V"], r["v2_V"], r["v3_V"], r["v_start_V"], (i_dark, 0.0))["i_A"]
                / r["i_true_A"] - 1.0) for r in rows),
        "decades": math.log10(cur[-1] / cur[1]),
        "dr_db": dr,
        "dr_formula_db": m["dr_formula_db"], "cvdr_db": m["cvdr_db"],
        "dr_steps_db": 20 * math.log10(2 ** cd.steps),
        "dr_paper_expected_db": 112.0, "dr_paper_measured_db": 100.0,
        "i_max_A": i_max_sim, "i_max_model_A": m["i_max_A"], "i_min_A": m["i_min_A"],
        "v_noise_V": m["v_noise_V"],
        "knee": {"i_knee_model_A": knee, "largest_unflipped_A": max(held),
                 "smallest_flipped_A": min(flipped)},
        "knee_other_v0": {"v0_V": alt.pixel.v0, "i_knee_model_A": alt_knee,
                          "bracket": KNEE_BRACKET,
                          "flipped": [_flipped(alt, res_alt, k) for k in range(len(alt_cur))]},
        "i_dark_A": i_dark, "dark_slope_A_per_V": dark[1],
        "dark_current_vs_voltage": dark_current_vs_voltage(design, backend=backend),
        "sweep": rows,
        "n_runs": 2, "n_cached": sum(bool(r.meta.get("cached")) for r in (res, res_alt)),
        "wall_s": time.perf_counter() - t0,
    }
