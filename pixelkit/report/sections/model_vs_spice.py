"""Analytic model vs SPICE: the simulation experiment of [Thesis2019] (fig. A.1 - A.3) on the design.

Independent paths side by side: SPICE circuit elements (the generated pixel, its
column and the GS sequence in ngspice) against the analytic C(V) discharge of the
PD node (``physics.discharge``; PD junction + EC/TG diffusions + dark current).
The discharge curves re-read the experiment's own SPICE runs (cache hits).
"""
from __future__ import annotations

import numpy as np

from ...circuits.testbench import timings
from ...constants import Q
from ...experiments.thesis import COARSE, fig_a1, sweep
from ...physics import discharge
from ...physics.dark import dark_current
from ...physics.subpixel import pd_node
from ...regress import TOLERANCES
from ..figures import axes, save
from ..names import label
from . import Checked, Figure, Section, Table

TITLE = "Analytic model vs SPICE (fig. A.1 - A.3)"
UNITS = {"_A": "A", "_V": "V", "_frac": "1", "ratio": "1"}
NODES = {"primary": "x1.xp.pd", "secondary": "x1.xs0.pd"}


def _unit(name: str) -> str:
    return next((u for k, u in UNITS.items() if name.endswith(k)), "1")


def _get(result: dict, name: str) -> float:
    node = result
    for part in name.split("."):
        node = node[part]
    return float(node)


def _transfer(ctx, exp):
    fig, (a, b) = axes(2, 9, 3.4)
    for ax, w, key in ((a, "primary", "i_mid_A"), (b, "secondary", "i_5pct_A")):
        e = exp[w]
        i, s = np.asarray(e["sweep_A"]), np.asarray(e["signal_V"])
        o = np.argsort(i)
        ax.plot(i[o] * 1e12, s[o] * 1e3, "o-", ms=3, label="SPICE: column signal")
        ax.axhline(e["pedestal_V"] * 1e3, color="0.5", lw=0.8, ls=":",
                   label=f"pedestal {e['pedestal_V'] * 1e3:.1f} mV (zero light)")
        tgt = e["pedestal_V"] + e["target_frac"] * e["swing_V"]
        ax.axhline(tgt * 1e3, color="C3", lw=0.8, ls="--")
        ax.axvline(e[key] * 1e12, color="C3", lw=0.8, ls="--",
                   label=f"{e['target_frac'] * 100:g} % of swing at {e[key] * 1e12:.1f} pA")
        ax.set_xlabel("photocurrent (pA)")
        ax.set_ylabel("double-sampled signal (mV)")
        ax.set_title(f"{w}: transfer ({exp['t_window_s'] * 1e6:g} us window)")
        ax.legend(fontsize=7)
    path = save(fig, ctx.figure("transfer_curves.png"))
    return Figure(path.name, "Transfer curves: double-sampled column signal against photocurrent (SPICE), "
                             "with the mid-scale (primary) and 5 % (secondary) points (fig. A.2, A.3)")


def _discharge(ctx, exp):
    """V(pd) during exposure, SPICE against the analytic C(V) discharge, for the coarse sweep."""
    d = ctx.design
    ip = exp["primary"]["sweep_A"][:COARSE]
    is_ = exp["secondary"]["sweep_A"][:COARSE]
    runs = sweep(d, ip, is_, ctx.backend, ctx.jobs, "coarse")
    tm = timings(d, exp["t_window_s"])
    fig, axs = axes(2, 9, 3.4)
    rows = []
    for ax, w, cur in ((axs[0], "primary", ip), (axs[1], "secondary", is_)):
        node = pd_node(d, w, parasitics=True)
        sub = getattr(d, w)
        i_d = dark_current(sub.area, sub.perimeter, d.temperature, d.tech.photodiode)
        t = tm[w]
        t0, t1 = t.t_reset + t.edge + 50e-9, t.t_tx - t.t_tg
        for k, (r, i) in enumerate(zip(runs, cur)):
            m = (r.time >= t0) & (r.time <= t1)
            tt, v = r.time[m], r[NODES[w]][m]
            v0 = float(r.at(NODES[w], t0))
            model = discharge.voltage(tt - t0, node, v0, i + i_d)
            ax.plot((tt - t0) * 1e6, v, color=f"C{k % 10}", lw=1.0)
            ax.plot((tt - t0) * 1e6, model, color=f"C{k % 10}", lw=0.8, ls="--")
            drop_s, drop_m = v0 - v, v0 - model
            ok = (drop_s >= 0.1 * d.pixel.swing) & (drop_s <= 0.9 * d.pixel.swing)
            err = float(np.max(np.abs(drop_m[ok] - drop_s[ok]) / drop_s[ok])) if ok.any() else None
            rows.append([w, i * 1e12, float(v[-1]), float(model[-1]), "-" if err is None else err * 100])
        ax.set_xlabel("time in exposure (us)")
        ax.set_ylabel("V(PD) (V)")
        ax.set_title(f"{w}: SPICE (solid) vs analytic C(V) (dashed)")
    path = save(fig, ctx.figure("discharge_curves.png"))
    return (Figure(path.name, "PD discharge during exposure for the sweep's photocurrents: SPICE (solid) against "
                              "the analytic C(V) discharge (dashed)"),
            Table("discharge_model_vs_spice", "Discharge: end-of-exposure V(PD) and worst error over 10 - 90 % "
                  "of swing", ["subpixel", "photocurrent (pA)", "V(PD) SPICE (V)", "V(PD) analytic (V)",
                               "worst error (%)"], rows))


def _fig_a1(ctx, a1):
    _, r = fig_a1(ctx.design, ctx.backend)   # the experiment's own run, from the cache
    fig, (ax,) = axes(1, 6, 3.2)
    ax.plot(r.time * 1e6, r["pdp"], label=f"15.1 x 13.55 um PD, {a1['i_primary_A'] * 1e12:.0f} pA")
    ax.plot(r.time * 1e6, r["pds"], ls="--", label=f"5 x 5 um PD, {a1['i_secondary_A'] * 1e12:.0f} pA (ratio C_C)")
    ax.set_xlabel("time (us)")
    ax.set_ylabel("V(PD) (V)")
    ax.set_title(f"fig. A.1: worst difference {a1['max_diff_frac'] * 100:.2f} % of swing")
    ax.legend(fontsize=7)
    path = save(fig, ctx.figure("fig_a1.png"))
    return Figure(path.name, "Fig. A.1: both bare PDs, currents in the ratio C_C, discharge together")


def build(ctx) -> Section:
    exp = ctx.experiment()
    figs = [_transfer(ctx, exp)]
    f2, t_dis = _discharge(ctx, exp)
    figs += [f2, _fig_a1(ctx, exp["fig_a1"])]
    points = []
    for w in ("primary", "secondary"):
        e = exp[w]
        for i, s in sorted(zip(e["sweep_A"], e["signal_V"])):
            points.append([w, i * 1e12, s * 1e3, (s - e["pedestal_V"]) / e["swing_V"]])
    exp_d = ctx.design.experiment
    key = [["primary photocurrent at mid-scale (pA)", exp["primary"]["i_mid_A"] * 1e12, "1400"],   # as printed
           ["secondary photocurrent at 5 % (pA)", exp["secondary"]["i_5pct_A"] * 1e12, "52"],
           ["i_mid / i_5pct", exp["ratio"], "1400 / 52"],
           [f"linear ideal ({exp_d.mid_fraction:g}/{exp_d.low_fraction:g}) C_C", exp["ratio_ideal"], "-"],
           ["primary column swing (mV)", exp["primary"]["swing_V"] * 1e3, "-"],
           ["secondary column swing (mV)", exp["secondary"]["swing_V"] * 1e3, "-"],
           [f"primary {label('pedestal')}", exp["primary"]["pedestal_V"] * 1e3, "-"],
           [f"secondary {label('pedestal')}", exp["secondary"]["pedestal_V"] * 1e3, "-"],
           ["analytic vs SPICE discharge, worst (%)", exp["model_vs_spice"]["max_err_frac"] * 100, "-"],
           ["fig. A.1 worst difference (% of swing)", exp["fig_a1"]["max_diff_frac"] * 100, "-"]]
    if ctx.reference:
        key_table = Table("mvs_key_points", "The 5 % / mid-scale point, [Thesis2019] beside the kit",
                          ["figure", "kit", "[Thesis2019]"], key)
    else:
        key_table = Table("mvs_key_points", "The 5 % / mid-scale point", ["figure", "value"], [r[:2] for r in key])
    checked = [Checked(f"model_vs_spice.{n}", _get(exp, n), _unit(n), tr, ta) for n, (tr, ta) in TOLERANCES.items()]
    dark_e = {w: dark_current(getattr(ctx.design, w).area, getattr(ctx.design, w).perimeter, ctx.design.temperature,
                              ctx.design.tech.photodiode) * exp["t_window_s"] / Q for w in NODES}
    text = [f"Both subpixels are exposed over {exp['t_window_s'] * 1e6:g} us with a sweep of photocurrents "
            f"({exp['n_runs']} SPICE runs), read through the column with the global-shutter sequence and "
            "double-sampled. The analytic model (C(V) discharge of the PD node) is an independent path: it "
            "shares only the junction parameters with the SPICE deck.",
            f"At zero photocurrent the column shows the pedestal ({exp['primary']['pedestal_V'] * 1e3:.1f} / "
            f"{exp['secondary']['pedestal_V'] * 1e3:.1f} mV, primary / secondary): the double sampling's offset "
            "from switch charge injection and feedthrough and the PD / FD reset levels, not dark current, which "
            f"collects {dark_e['primary']:.2g} / {dark_e['secondary']:.2g} e- in the window. Fractions of the "
            "swing are counted from it."]
    return Section(TITLE, text=text, figures=figs, checked=checked,
                   tables=[key_table,
                           t_dis,
                           Table("transfer_points", "Transfer curves (SPICE; at 0 pA the signal is the pedestal)",
                                 ["subpixel", "photocurrent (pA)", "signal (mV)", "fraction of swing above the "
                                  "pedestal"], points)],
                   data={k: exp[k] for k in ("primary", "secondary", "ratio", "ratio_ideal", "model_vs_spice",
                                             "fig_a1", "t_window_s")})
