"""Sizing section: the mask opening and integration times at both model levels, the binding
constraints (slack of every constraint at the solution), the SPICE verification at the real
integration times, and the sensitivity table (full profile only).

Independent path: the verification simulates the sized design over its own 1 ms / 10 ms-scale
exposures (``optimize.flow.verify``), not the short-window experiment the sizing was solved from.
"""
from __future__ import annotations

import numpy as np

from ...fileio import write_atomic
from ...optimize.flow import WHY, sensitivity, sized_design_text, verify
from ...optimize.levels import analytic_curves, spice_curves
from ...optimize.sizing import _bounds, light, solve
from ..figures import axes, save
from . import Checked, Figure, Section, Table

TITLE = "Sizing: mask opening and integration times"
ACTIVE = 1e-3   # relative slack below which a constraint is binding (IPOPT tol 1e-10)


def _slacks(design, curves, s: dict) -> list[list]:
    """Every constraint at the solution: its bound, the sized value, the relative slack, binding or not."""
    ts, tp, checks, q = _bounds(design, curves, light(design))
    m = design.sizing.margin
    t_s, t_p, a = s["t_int_secondary_s"], s["t_int_primary_s"], s["mask_open_m2"]
    e = design.experiment
    rows = [["criterion primary (f_p = mid-scale)", e.mid_fraction * 100, e.mid_fraction * 100, "% swing", 0.0],
            ["criterion secondary (f_s = 5 %)", e.low_fraction * 100, e.low_fraction * 100, "% swing", 0.0]]
    for name, (kind, v) in ts.items():
        if name.startswith("opening"):
            continue
        slack = t_s / v - 1 if kind == "lo" else v / t_s - 1
        rows.append([f"{name} (t_secondary {'>=' if kind == 'lo' else '<='})", v * 1e3, t_s * 1e3, "ms", slack])
    v = tp["motion"][1]
    rows.append(["motion (t_primary <=)", v * 1e3, t_p * 1e3, "ms", v / t_p - 1])
    lo = q["min_open"] * (1 + m)
    rows.append(["opening_min (A_open >=)", lo * 1e12, a * 1e12, "um2", a / lo - 1])
    rows.append(["opening_max (A_open <= A_pd)", design.secondary.area * 1e12, a * 1e12, "um2",
                 design.secondary.area / a - 1])
    if design.sizing.t_ratio:
        rows.append(["t_ratio (t_s = ratio t_p)", design.sizing.t_ratio, s["t_ratio"], "", 0.0])
    hmax = q["q_head_max"] * (1 - m)
    rows.append(["headlight_max (Q_head <=)", hmax * 1e15, q["q_head"] * 1e15, "fC", hmax / q["q_head"] - 1])
    hmin = design.sizing.headlight_snr * q["q_noise"] * (1 + m)
    rows.append(["headlight_snr (Q_head >=)", hmin * 1e15, q["q_head"] * 1e15, "fC", q["q_head"] / hmin - 1])
    return [r[:4] + [r[4] * 100, "binding" if abs(r[4]) < ACTIVE else "slack"] for r in rows]


def _figure(ctx, curves: dict, slack_rows, s: dict):
    fig, (a, b) = axes(2, 10, 3.6)
    tsv = s["t_int_secondary_s"] * 1e3
    bounds = [r for r in slack_rows if r[3] == "ms" and "t_secondary" in r[0]]
    for k, r in enumerate(bounds):
        lo = ">=" in r[0]
        edge = r[1] / 100 if lo else r[1] * 100
        a.barh(k, abs(edge - r[1]), left=min(edge, r[1]), height=0.5, color="C3", alpha=0.25)
        a.plot([r[1]], [k], "|", color="C3", ms=14)
    a.axvline(tsv, color="C0", lw=1.2, label=f"sized t_secondary {tsv:.3g} ms")
    a.set_xscale("log")
    a.set_yticks(range(len(bounds)), [r[0].split(" ")[0] for r in bounds])
    a.set_xlim(min(r[1] for r in bounds + [[0, tsv]]) / 5, max(r[1] for r in bounds + [[0, tsv]]) * 5)
    a.set_xlabel("t_secondary (ms)")
    a.set_title("bounds on t_secondary (shaded: excluded)")
    a.legend(fontsize=7)
    for lvl, c in curves.items():
        ls = "-" if lvl == "spice" else "--"
        b.plot(c.q_primary * 1e15, c.f_primary * 100, "C0" + ls, label=f"primary, {lvl}")
        b.plot(c.q_secondary * 1e15, c.f_secondary * 100, "C1" + ls, label=f"secondary, {lvl}")
    e = ctx.design.experiment
    b.axhline(e.mid_fraction * 100, color="C0", lw=0.6, ls=":")
    b.axhline(e.low_fraction * 100, color="C1", lw=0.6, ls=":")
    b.set_xscale("log")
    b.set_xlabel("collected charge (fC)")
    b.set_ylabel("signal (% of swing)")
    b.set_title("the two model levels (mid-scale / 5 % dotted)")
    b.legend(fontsize=7)
    path = save(fig, ctx.figure("sizing.png"))
    return Figure(path.name, "Sizing: the closed-form bounds each constraint puts on the secondary integration "
                             "time with the sized value, and the signal-vs-charge curves of both model levels")


def build(ctx) -> Section:
    d = ctx.design
    if d.optics is None or d.scene is None:
        return Section.unavailable(TITLE, "the design has no [optics] / [scene] table to size against")
    exp = ctx.experiment()
    curves = {"analytic": analytic_curves(d), "spice": spice_curves(d, exp)}
    levels = {k: solve(d, c) for k, c in curves.items()}
    chosen = levels[d.sizing.level]
    ctx.progress("sizing: SPICE verification at the sized integration times")
    v = verify(d, chosen, exp)
    sized = ctx.figure("sized_design.toml")
    write_atomic(sized, sized_design_text(d, chosen, sized))
    rows = [("C_M = A_pd / A_open", "c_m", 1), ("mask opening (um2)", "mask_open_m2", 1e12),
            ("t_int primary (us)", "t_int_primary_s", 1e6), ("t_int secondary (ms)", "t_int_secondary_s", 1e3),
            ("t_secondary / t_primary", "t_ratio", 1), ("trace at v_min (px)", "trace_px_at_speed_min", 1),
            ("motion at v_max, primary (px)", "motion_px_primary", 1),
            ("dark charge, secondary (frac of full)", "dark_frac_secondary", 1),
            ("headlight (frac of swing)", "headlight_frac", 1)]
    result = Table("sizing_result", f"Sized values at both model levels ({d.sizing.level} level chosen)",
                   ["figure", "analytic", "SPICE curves"],
                   [[lbl, levels["analytic"][k] * u, levels["spice"][k] * u] for lbl, k, u in rows])
    slack_rows = _slacks(d, curves[d.sizing.level], chosen)
    slack = Table("sizing_constraints", f"Constraints at the {d.sizing.level}-level solution "
                  f"(margin {d.sizing.margin:g} included in the bounds)",
                  ["constraint", "bound", "sized value", "unit", "slack (%)", "state"], slack_rows)
    ver = Table("sizing_verify", "SPICE verification at the sized integration times (background light)",
                ["subpixel", "t_int", "photocurrent (pA)", "signal (% of swing)", "target (% of swing)"],
                [["primary", f"{v['t_int_primary_s'] * 1e6:.1f} us", v["i_primary_A"] * 1e12,
                  v["primary_frac"] * 100, d.experiment.mid_fraction * 100],
                 ["secondary", f"{v['t_int_secondary_s'] * 1e3:.3g} ms", v["i_secondary_A"] * 1e12,
                  v["secondary_frac"] * 100, d.experiment.low_fraction * 100]])
    tables = [result, slack, ver]
    data = {"levels": levels, "verify": v, "constraints": slack_rows}
    if ctx.quick:
        sens_note = "The sensitivity table (re-sizing at +-10 % C_j, +-20 % SF bias, each corner, +-10 K) " \
                    "is skipped in the quick profile: it re-runs the simulation experiment for every variant."
        tables.append(Table("sizing_sensitivity", "Sensitivity: skipped in the quick profile",
                            ["variant", "note"], [["all", "skipped (--quick)"]]))
    else:
        ctx.progress("sizing: sensitivity (re-sizing each variant)")
        sens = sensitivity(d, levels["spice"], ctx.backend)
        data["sensitivity"] = sens
        sens_note = "The sensitivity table re-sizes the design (SPICE level) for each variant."
        tables.append(Table("sizing_sensitivity", "Sensitivity of the sizing (SPICE level, re-sized per variant)",
                            ["variant", "C_M", "C_M change (%)", "t_int primary (us)", "t_primary change (%)",
                             "t_int secondary (ms)"],
                            [[r["variant"], r["c_m"], r["c_m_change_frac"] * 100, r["t_int_primary_s"] * 1e6,
                              r["t_primary_change_frac"] * 100, r["t_int_secondary_s"] * 1e3] for r in sens]))
    binding = [r[0].split(" ")[0] for r in slack_rows if r[5] == "binding" and r[3] != "% swing"] or ["none"]
    text = [f"The secondary mask opening and both integration times solved with casadi/IPOPT at the analytic "
            f"level (PD node C(V)) and at the SPICE level (the simulation experiment's double-sampled column "
            f"curves); the {d.sizing.level} level is chosen. Besides the two criterion equalities (mid-scale / 5 %), the binding "
            f"constraints are: {', '.join(binding)}. "
            f"The sized design file is written beside this report (sized_design.toml), not in the design's folder.",
            f"Why the levels differ: {WHY}",
            f"Independent check: the sized design simulated in SPICE over its real integration times at the "
            f"background light reaches {v['primary_frac'] * 100:.1f} % (primary, target "
            f"{d.experiment.mid_fraction * 100:g} %) and {v['secondary_frac'] * 100:.2f} % (secondary, target "
            f"{d.experiment.low_fraction * 100:g} %) of swing.", sens_note]
    # Tolerances: the solution moves with the curves it is solved from; 1 % on the sizes is the
    # interpolation noise of the experiment's curve, 1 % / 0.5 % of swing on the verification
    # the sampling-window resolution of the long exposures.
    checked = [Checked("sizing.c_m", chosen["c_m"], "1", tol_rel=0.01),
               Checked("sizing.mask_open_m2", chosen["mask_open_m2"], "m2", tol_rel=0.01),
               Checked("sizing.t_int_primary_s", chosen["t_int_primary_s"], "s", tol_rel=0.01),
               Checked("sizing.t_int_secondary_s", chosen["t_int_secondary_s"], "s", tol_rel=0.01),
               Checked("sizing.verify.primary_frac", v["primary_frac"], "1", tol_abs=0.01,
                       note="SPICE at the sized t_int, target mid-scale"),
               Checked("sizing.verify.secondary_frac", v["secondary_frac"], "1", tol_abs=0.005,
                       note="SPICE at the sized t_int, target 5 %")]
    return Section(TITLE, text=text, tables=tables, figures=[_figure(ctx, curves, slack_rows, chosen)],
                   checked=checked, data=data, files=[sized.name])
