"""The thesis's [Thesis2019] simulation experiment (fig. A.1 - A.3), run on a design.

Both subpixels are exposed over the same short window (the design's
``experiment.t_window``; the thesis's plots span ~20 us) with a sweep of
photocurrents, read through the column with the global-shutter sequence, and
the double-sampled column signal (reset level - signal level) is measured.

- pedestal: the double-sampled signal at zero photocurrent (switch charge injection and
  feedthrough, the PD / FD reset offsets; not dark current, which adds a few electrons in the
  window)
- swing: the signal at saturation minus the pedestal, per subpixel kind
- i_mid: the primary photocurrent at ``mid_fraction`` of its swing
- i_5pct: the secondary photocurrent at ``low_fraction`` of its swing
- model_vs_spice: the analytic C(V) discharge of the PD node (PD junction +
  EC/TG diffusions and overlaps + dark current) against SPICE's V(pd) during
  exposure, worst relative error over 10 - 90 % of the design's swing
- fig_a1: two bare PDs with currents in the ratio C_C, worst difference
"""
from __future__ import annotations

import time

import numpy as np

from ..circuits.testbench import dual_pixel_bench, pd_pair_bench, timings
from ..measure.pixel import double_sampled, target_current
from ..physics import discharge
from ..physics.dark import dark_current
from ..physics.subpixel import pd_node
from ..spice import simulate_many

COARSE = 9
REFINE = 6
#: A measured column swing below this is noise-level (a few hundred electrons on the
#: column): i_mid, i_5pct, their ratio and everything sized from them are not computed.
MIN_MEASURED_SWING_V = 0.01


def _i_max(design, which: str, v_end: float = 0.5) -> float:
    """Current that takes the PD node from its reset level to ``v_end`` in the window."""
    node = pd_node(design, which, parasitics=True)
    q = float(node.charge(design.pixel.v_pd_reset) - node.charge(v_end))
    return q / design.experiment.t_window


def _signals(design, results, tm):
    n = design.secondary_per_pixel
    p = [double_sampled(r, "col_p", tm["primary"]) for r in results]
    s = [[double_sampled(r, f"col_s{k}", tm["secondary"]) for k in range(n)] for r in results]
    return np.array(p), np.array(s)


def sweep(design, ip, is_, backend="batch", jobs=None, tag="sweep"):
    nets = [dual_pixel_bench(design, a, b, title=f"{tag}{k}") for k, (a, b) in enumerate(zip(ip, is_))]
    for k, (net, a, b) in enumerate(zip(nets, ip, is_)):  # the operating point in the user's terms
        net.meta["what"] = (f"the dual-pixel bench of {design.name} at I_primary = {a * 1e9:.4g} nA, "
                            f"I_secondary = {b * 1e12:.4g} pA ({tag} sweep, point {k + 1} of {len(nets)}; "
                            f"pixel.v_pd_reset = {design.pixel.v_pd_reset:g} V, "
                            f"pixel.v_fd_reset = {design.pixel.v_fd_reset:g} V, corner {design.corner_name}, "
                            f"{design.temperature - 273.15:g} degC)")
    return simulate_many(nets, backend=backend, jobs=jobs, failed="keep")


def _kept(tag, ip, is_, res, failed: list):
    """The points that simulated; the others go to ``failed`` with ngspice's message (and the
    node where the run went wrong): one bad point never stops the experiment."""
    from ..errors import SimulationError
    ok = [k for k, r in enumerate(res) if not isinstance(r, SimulationError)]
    failed += [{"sweep": tag, "iph_primary_A": float(ip[k]), "iph_secondary_A": float(is_[k]),
                "message": res[k].message, "folder": res[k].details()["folder"], "tried": res[k].tried}
               for k in range(len(res)) if k not in ok]
    if tag == "coarse" and (0 not in ok or len(ok) < 3):
        raise next(r for r in res if isinstance(r, SimulationError))   # no dark point or too few to go on
    return ip[ok], is_[ok], [res[k] for k in ok]


def model_vs_spice(design, results, currents, which: str, tm) -> float:
    """Worst relative error of the analytic discharge over 10-90 % of the swing."""
    node = pd_node(design, which, parasitics=True)
    sub = getattr(design, which)
    i_d = dark_current(sub.area, sub.perimeter, design.temperature, design.tech.photodiode)
    name = "x1.xp.pd" if which == "primary" else "x1.xs0.pd"
    t = tm[which]
    t0, t1 = t.t_reset + t.edge + 50e-9, t.t_tx - t.t_tg
    swing = design.pixel.swing
    worst = 0.0
    for r, i in zip(results, currents):
        m = (r.time >= t0) & (r.time <= t1)
        tt, v = r.time[m], r[name][m]
        v0 = float(r.at(name, t0))
        model = discharge.voltage(tt - t0, node, v0, i + i_d)
        drop_s, drop_m = v0 - v, v0 - model
        ok = (drop_s >= 0.1 * swing) & (drop_s <= 0.9 * swing)
        if ok.any():
            worst = max(worst, float(np.max(np.abs(drop_m[ok] - drop_s[ok]) / drop_s[ok])))
    return worst


def fig_a1(design, backend="batch"):
    """Fig. A.1: bare PDs with I_p1 / I_p2 = C_C discharge together."""
    v0, swing = design.tech.photodiode.reset_bias, design.pixel.swing
    p, s = pd_node(design, "primary"), pd_node(design, "secondary")
    c_c = float(p.capacitance(v0) / s.capacitance(v0))
    t_stop = 20e-6
    i_p = float(p.charge(v0) - p.charge(v0 - swing)) / t_stop
    r = simulate_many([pd_pair_bench(design, i_p, i_p / c_c, t_stop, v0)], backend=backend, jobs=1)[0]
    diff = np.abs(r["pdp"] - r["pds"])
    return {"c_c": c_c, "i_primary_A": i_p, "i_secondary_A": i_p / c_c, "t_stop_s": t_stop,
            "max_diff_frac": float(diff.max() / swing)}, r


def _check_swing(design, swing_p: float, swing_s: float) -> None:
    from ..errors import PixelkitError
    for which, sw in (("primary", swing_p), ("secondary", swing_s)):
        if not np.isfinite(sw) or sw < MIN_MEASURED_SWING_V:
            raise PixelkitError(
                f"{design.source}: the measured {which} swing at the column is {sw:.3g} V, below "
                f"{MIN_MEASURED_SWING_V * 1e3:g} mV: too small to mean anything, so i_mid, i_5pct and the "
                "figures built on them are not computed (check pixel.swing, pixel.sf_bias, pixel.column_cap "
                "and the reset levels)")


def run_experiment(design, backend: str = "batch", jobs: int | None = None) -> dict:
    t_start = time.perf_counter()
    exp = design.experiment
    tm = timings(design, exp.t_window)
    ip = np.linspace(0, _i_max(design, "primary"), COARSE)
    is_ = np.linspace(0, _i_max(design, "secondary"), COARSE)
    failed: list = []
    ip, is_, res = _kept("coarse", ip, is_, sweep(design, ip, is_, backend, jobs, "coarse"), failed)
    sp, ss = _signals(design, res, tm)
    dark_p, dark_s = sp[0], ss[0, 0]
    swing_p, swing_s = sp.max() - dark_p, ss[:, 0].max() - dark_s
    _check_swing(design, float(swing_p), float(swing_s))
    tgt_p, tgt_s = dark_p + exp.mid_fraction * swing_p, dark_s + exp.low_fraction * swing_s
    # refine inside the brackets of both targets
    kp = int(np.searchsorted(np.maximum.accumulate(sp), tgt_p))
    ks = int(np.searchsorted(np.maximum.accumulate(ss[:, 0]), tgt_s))
    ip2 = np.linspace(ip[kp - 1], ip[kp], REFINE + 2)[1:-1]
    is2 = np.linspace(is_[ks - 1], is_[ks], REFINE + 2)[1:-1]
    ip2, is2, res2 = _kept("refine", ip2, is2, sweep(design, ip2, is2, backend, jobs, "refine"), failed)
    sp2, ss2 = _signals(design, res2, tm) if res2 else (np.zeros(0), np.zeros((0, design.secondary_per_pixel)))
    all_ip, all_sp = np.concatenate([ip, ip2]), np.concatenate([sp, sp2])
    all_is, all_ss = np.concatenate([is_, is2]), np.concatenate([ss[:, 0], ss2[:, 0]])
    i_mid = target_current(all_ip, all_sp, tgt_p)
    i_low = target_current(all_is, all_ss, tgt_s)
    runs = res + res2
    err_p = model_vs_spice(design, runs, np.concatenate([ip, ip2]), "primary", tm)
    err_s = model_vs_spice(design, runs, np.concatenate([is_, is2]), "secondary", tm)
    a1, a1_result = fig_a1(design, backend)
    c_c = a1["c_c"]
    n_cached = sum(bool(r.meta.get("cached")) for r in runs + [a1_result])
    spread = float(np.max(np.abs(ss - ss[:, :1])))
    return {
        "design": design.name,
        "t_window_s": exp.t_window,
        "backend": backend,
        "ngspice_version": runs[0].meta["ngspice_version"],
        "primary": {"i_mid_A": i_mid, "swing_V": float(swing_p), "pedestal_V": float(dark_p),
                    "target_frac": exp.mid_fraction, "sweep_A": all_ip.tolist(), "signal_V": all_sp.tolist()},
        "secondary": {"i_5pct_A": i_low, "swing_V": float(swing_s), "pedestal_V": float(dark_s),
                      "target_frac": exp.low_fraction, "sweep_A": all_is.tolist(), "signal_V": all_ss.tolist(),
                      "subpixel_spread_V": spread},
        "ratio": i_mid / i_low,
        "ratio_ideal": exp.mid_fraction / exp.low_fraction * c_c,
        "model_vs_spice": {"max_err_frac": max(err_p, err_s), "primary": err_p, "secondary": err_s},
        "fig_a1": a1,
        "n_runs": len(runs) + 1,
        "failed_points": failed,
        "retried": [dict(r.meta["retried"], deck=r.meta["title"]) for r in runs + [a1_result]
                    if r.meta.get("retried")],
        "n_cached": n_cached,
        "wall_s": time.perf_counter() - t_start,
    }
