"""The 4T pixel's experiment (``pixelkit simulate designs/pixel4t_gf180.toml``): every figure of the
role measurements (``rolepix``) beside the closed form it is checked against (``model``,
``physics.ppd``), and the transfer curves:

- conversion gain, full well (at the output; the PPD's own from its charge node against
  ``C_PPD V_pin`` and the light term), read noise (.noise; FD's kT/C that true CDS removes), image lag,
  dark current, power;
- *lag vs TG high level*: the charge the read's transfer leaves in the PPD, SPICE (its charge node)
  against ``Ppd.residual``, at TG levels from the design's down to where a barrier appears;
- *transfer curve*: the PPD's charge through one long TG pulse at a level where the barrier holds the
  last electrons, SPICE against the closed form ``Q(t)`` from the moment the barrier regime begins.
"""
from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from ...constants import Q
from ...progress import step
from . import model

#: TG high levels of the lag curve, below the design's (V)
TG_STEPS = (0.0, -0.3, -0.5, -0.6, -0.7, -0.8)


def _residual_after_read(design, n_bright: float, backend: str) -> float:
    """Electrons left in the PPD right after a bright frame's read transfer (SPICE, the charge node)."""
    from ...circuits.cds import cds_bench, timing_of
    from ...circuits.pixel4t import ppd_model
    from ...rolepix.run import run
    from ...rolepix.signal import current_for, flush_exposure
    from .model import tg_channel
    cell = design.cell()
    tw, t0 = design.experiment.t_window, flush_exposure(design)
    ex = [t0, tw]
    net = cds_bench(design, cell, ex, [[0.0, current_for(design, n_bright, tw)]], title="p4t_residual",
                    saves=("x0.q",))
    (r,) = run([net], design, None, backend)
    tm, st = timing_of(design), net.meta["frames"]["starts"]
    t = st[1] + tm.frame(tw).t_read + tm.tg[1] + 3 * tm.edge
    return -float(r.at("v(x0.q)", t)) * ppd_model(design, tg_channel(design)).c / Q


def lag_curve(design, n_bright: float, backend: str = "batch") -> list[dict]:
    from ...circuits.cds import tg_high
    from ...circuits.pixel4t import ppd_model
    from .model import tg_channel
    p = ppd_model(design, tg_channel(design))
    v0, rows = tg_high(design), []
    for dv in TG_STEPS:
        d = replace(design, levels=replace(design.levels, tg_high=v0 + dv))
        rows.append({"tg_high_V": v0 + dv, "barrier_V": p.v_pin - p.phi_b(v0 + dv), "tau_s": p.tau(v0 + dv),
                     "left_spice_e": _residual_after_read(d, n_bright, backend),
                     "left_model_e": p.residual(n_bright * Q, design.timing.t_tg, v0 + dv) / Q})
    return rows


def transfer_curve(design, n0: float, backend: str = "batch") -> dict:
    """The PPD's charge through a TG pulse 20 x the design's at the TG level where tau is nearest the
    design's TG pulse: SPICE against ``Q(t)`` (closed form) from the moment Q falls below the barrier
    charge C_PPD (V_pin - phi_B) less 3 Q_T."""
    from ...circuits.cds import cds_bench, timing_of, tg_high
    from ...circuits.pixel4t import ppd_model
    from ...rolepix.run import run
    from ...rolepix.signal import current_for, flush_exposure
    from .model import tg_channel
    p = ppd_model(design, tg_channel(design))
    t_tg = design.timing.t_tg
    levels = np.arange(tg_high(design), 1.0, -0.01)
    v = float(levels[np.argmin([abs(np.log(p.tau(x) / t_tg)) for x in levels])])
    long_tg = 20 * t_tg
    d = replace(design, levels=replace(design.levels, tg_high=v), timing=replace(design.timing, t_tg=long_tg))
    tw, t0 = max(design.experiment.t_window, 2 * long_tg), flush_exposure(d)
    ex = [t0, tw]
    net = cds_bench(d, d.cell(), ex, [[0.0, current_for(d, n0, tw)]], title="p4t_transfer", saves=("x0.q",))
    (r,) = run([net], d, None, backend)
    tm, st = timing_of(d), net.meta["frames"]["starts"]
    on = st[1] + tm.frame(tw).t_read + tm.tg[0] + tm.edge
    t = np.linspace(on, on + long_tg - tm.edge, 400)
    q = -np.interp(t, r.time, r["v(x0.q)"]) * p.c
    q_b = p.c * (p.v_pin - p.phi_b(v)) - 3 * p.q_t
    k = int(np.argmax(q < q_b)) if np.any(q < q_b) else None
    if k is None or q_b <= 0:
        return {"tg_high_V": v, "tau_s": p.tau(v), "note": "no barrier regime at this level"}
    model_q = np.array([p.residual(q[k], tt - t[k], v) for tt in t[k:]])
    err = (q[k:] - model_q) / Q
    return {"tg_high_V": v, "tau_s": p.tau(v), "t_start_s": float(t[k] - on), "q_start_e": float(q[k] / Q),
            "t_s": (t[k:] - on).tolist()[::20], "spice_e": (q[k:] / Q).tolist()[::20],
            "model_e": (model_q / Q).tolist()[::20], "max_abs_err_e": float(np.max(np.abs(err))),
            "max_rel_err_frac": float(np.max(np.abs(err) / np.maximum(model_q / Q, 10.0)))}


def ppd_full_well(design, backend: str = "batch") -> dict:
    """The PPD's own full well: its charge at the end of a saturating exposure (the ladder's top current,
    SPICE charge node) against ``Ppd.full_well`` at that photocurrent, and C_PPD V_pin in the dark."""
    from ...circuits.cds import cds_bench, timing_of
    from ...circuits.pixel4t import ppd_model
    from ...rolepix.run import run
    from ...rolepix.signal import current_for, flush_exposure
    from .model import tg_channel
    p = ppd_model(design, tg_channel(design))
    tw, t0 = design.experiment.t_window, flush_exposure(design)
    i_ph = current_for(design, 5 * p.full_well() / Q, tw)
    net = cds_bench(design, design.cell(), [t0, tw], [[0.0, i_ph]], title="p4t_ppd_full", saves=("x0.q",))
    (r,) = run([net], design, None, backend)
    tm, st = timing_of(design), net.meta["frames"]["starts"]
    t = st[1] + tm.frame(tw).light[1] - 2 * tm.edge
    return {"photocurrent_A": i_ph, "spice_e": -float(r.at("v(x0.q)", t)) * p.c / Q,
            "model_e": p.full_well(i_ph) / Q, "dark_model_e": p.full_well() / Q,
            "c_ppd_v_pin_e": p.c * p.v_pin / Q}


def run_pixel4t_experiment(design, backend: str = "batch", jobs: int | None = None) -> dict:
    from ...circuits.cds import tg_high
    from ...circuits.pixel4t import ppd_model
    from ...rolepix import suite
    from ...rolepix.noise import read_point
    from .model import tg_channel
    t0 = time.perf_counter()
    raw = suite.run_experiment_groups(design, "4T pixel", backend)
    figs = suite.figures(raw)
    op = read_point(design, backend)
    cg = model.conversion_gain(design, op["v_fd"], backend)
    p = ppd_model(design, tg_channel(design))
    n_bright = raw["lag"]["bright_e"]
    with step("4T pixel: lag vs TG level, transfer curve, PPD full well"):
        curve = lag_curve(design, n_bright, backend)
        transfer = transfer_curve(design, n_bright, backend)
        full = ppd_full_well(design, backend)
    lag_model = model.lag_electrons(p, n_bright * Q, design.timing.t_tg, tg_high(design))
    return {
        "design": design.name, "family": "pixel4t", "backend": backend,
        "conversion_gain_uV_per_e": figs["conversion_gain"] * Q * 1e6,
        "conversion_gain_model_uV_per_e": cg["cg_V_per_e"] * 1e6,
        "model": {"a_sf": cg["a_sf"], "c_fd_fF": cg["c_fd_F"] * 1e15, "v_fd_V": op["v_fd"],
                  "c_ppd_fF": p.c * 1e15, "v_pin_V": p.v_pin, "phi_b_V": p.phi_b(tg_high(design)),
                  "tau_s": p.tau(tg_high(design))},
        "full_well_e": figs["full_well"] / Q, "saturation_V": raw["signal"]["v_sat_V"],
        "ppd_full_well": full,
        "read_noise_e": figs["read_noise"] / Q,
        "fd_ktc_ncds_e": model.ktc_electrons(cg["c_fd_F"], design.temperature),
        "image_lag_pct": 100 * figs["image_lag"], "image_lag_e": raw["lag"]["lag_e"],
        "image_lag_model_e": lag_model["lag_e"],
        "dark_current_e_per_s": figs["dark_current"] / Q, "dark_current_model_e_per_s": (p.i_gen + p.i_dif) / Q,
        "power_chip_W": figs["power_chip"], "power_estimate_W": raw["power"]["estimate_W"],
        "lag_vs_tg": curve, "transfer_curve": transfer,
        "ladder": {"electrons": raw["signal"]["ladder"]["electrons"], "signal_V": raw["signal"]["ladder"]["signal_V"]},
        "wall_s": time.perf_counter() - t0,
    }
