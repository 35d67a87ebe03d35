"""Post-layout vs schematic: the design's figures on its schematic and on its post-layout view (the
wiring parasitics extracted from its own layout, ``layout.pex``), side by side.

Independent paths: the analytic figures take the extracted capacitances; the SPICE figures run the
post-layout netlists (the extracted couplings inside the pixel subcircuits, the column line's
extracted capacitance and the column-to-column couplings at the bench).
"""
from __future__ import annotations

from dataclasses import replace

from ...constants import Q
from .. import names as N
from . import Checked, Figure, Section, Table

TITLE = "Post-layout vs schematic"
_ARR = ("primary", "secondary")


def _figures(d, backend, jobs, quick) -> dict:
    from ...camera.spicenoise import output_cg, sf_gain
    from ...physics import fd
    from ...physics.noise import chain
    from ...techfit.ekv import models_for
    from ...physics.subpixel import model_table
    a = sf_gain(d)
    cg_sp = output_cg(d, backend=backend)
    mt = model_table(d, a, models_for(d))
    out = {"a_sf": a}
    for w in _ARR:
        r = fd.response(d, w, a, models_for(d))
        out[w] = {"c_fd_F": r["c_fd_F"], "c_pd_node_F": r["c_pd_node_F"], "cg_pd_V_per_e": r["cg_pd_V_per_e"],
                  "cg_fd_V_per_e": r["cg_fd_V_per_e"], "cg_out_V_per_e": r["cg_out_V_per_e"],
                  "cg_out_spice_V_per_e": cg_sp[w], "read_noise_e": chain(d, w, a, models_for(d))["pixel_e"],
                  "full_well_e": mt[w]["fwc_cv_e"]}
    out["crosstalk"] = _crosstalk(d, backend)
    from ...verify.measure import settling
    from .afe import gain_error
    out["afe_gain_error"] = gain_error(d, backend=backend)
    out["settling_V"] = settling(d, None, backend)
    out["frame"] = _frame(d, backend, jobs)
    from ...optimize.levels import analytic_curves, spice_curves
    from ...optimize.sizing import solve
    e = None
    if not quick:
        from ...experiments.thesis import run_experiment
        e = run_experiment(d, backend=backend, jobs=jobs)
        out["i_mid_A"], out["i_5pct_A"] = e["primary"]["i_mid_A"], e["secondary"]["i_5pct_A"]
    if d.optics is not None and d.scene is not None:
        spice = e is not None and d.sizing.level == "spice"
        out["sized"] = solve(d, spice_curves(d, e) if spice else analytic_curves(d))
    return out


def _frame(d, backend, jobs) -> list:
    """[array, row, column, photocurrent A, double-sampled signal V, AFE output V] of each pixel of the
    report's 2 x 2 frame (fig. 3.13 of [Thesis2019]) on ``d``'s view, at ``chip.frame.CONVERGED``
    tolerances: the section reports the difference of two views' frames, a few mV, and at the default
    tolerances the frame deck's own error is up to 3.9 mV of a -128 mV shift (the one deck holds both
    arrays, every column's AFE and two rows: its step sequence moves with any element, and a 1e-6 change
    of the column lines' capacitance moved it 0.4 mV, a 1e-3 change 2.3 mV); at CONVERGED it is the
    dual-pixel bench's to 0.04 mV (docs/post-layout.md, the 2 x 2 frame), for ~1.4 x the deck's CPU."""
    from ...chip.frame import CONVERGED
    from ...circuits.array import KINDS, PREFIX
    from ...measure.pixel import levels
    from .array import frame
    r, tm, ph = frame(d, backend, jobs, title="post_layout_frame" if d.post_layout is not None else "schematic_frame",
                      options=CONVERGED)
    out = []
    for kind in KINDS:
        cur = ph.iph_p if kind == "primary" else ph.iph_s
        for row in range(cur.shape[0]):
            for j in range(cur.shape[1]):
                node = f"col_{PREFIX[kind]}_{j}"
                sig, rst = levels(r, node, tm[kind], row)
                out.append([kind, row, j, float(cur[row][j]), rst - sig,
                            float(r.at(f"out_{node}", tm[kind].t_reset_level(row)))])
    return out


def _crosstalk(d, backend) -> dict:
    """Column-to-column: the secondary's column signal when only the primary is lit, over the primary's
    (SPICE, the dual-pixel bench); row-to-FD: the pedestal (zero light) of each array."""
    from ...circuits.testbench import dual_pixel_bench, timings
    from ...measure.pixel import double_sampled
    from ...spice import simulate_many
    i_p = 0.5 * d.pixel.swing * 40e-15 / d.experiment.t_window      # about half the primary's swing
    dark, lit = simulate_many([dual_pixel_bench(d, 0.0, 0.0, title="xt_dark"),
                               dual_pixel_bench(d, i_p, 0.0, title="xt_lit")], backend=backend)
    tm = timings(d, d.experiment.t_window)
    dp = double_sampled(lit, "col_p", tm["primary"]) - double_sampled(dark, "col_p", tm["primary"])
    ds = double_sampled(lit, "col_s0", tm["secondary"]) - double_sampled(dark, "col_s0", tm["secondary"])
    return {"col_to_col": ds / dp, "pedestal_p_V": double_sampled(dark, "col_p", tm["primary"]),
            "pedestal_s_V": double_sampled(dark, "col_s0", tm["secondary"])}


def _frame_figure(ctx, rows):
    from ..figures import axes, save
    fig, (ax,) = axes(1, 8, 3.2)
    labels = [f"{k[0]}{r}{j}" for k, r, j, *_ in rows]
    x = range(len(rows))
    ax.bar([i - 0.2 for i in x], [r[4] for r in rows], 0.4, label="schematic")
    ax.bar([i + 0.2 for i in x], [r[5] for r in rows], 0.4, label="post-layout")
    ax.set_xticks(list(x), labels, fontsize=7)
    ax.set_xlabel("array (p / s), row, column")
    ax.set_ylabel("V_rst - V_sig (mV)")
    ax.legend(fontsize=7)
    return save(fig, ctx.figure("post_layout_frame.png"))


def build(ctx) -> Section:
    d = ctx.design
    if d.tech.stack is None:
        return Section.needs_input(TITLE, "a technology with [stack]", f"technology {d.tech.name} has no process stack: "
                                          "no post-layout view (docs/post-layout.md)")
    from ...layout.pex.overlay import post_layout_view
    sch = replace(d, post_layout=None)
    post = post_layout_view(sch)
    f = {"schematic": _figures(sch, ctx.backend, ctx.jobs, ctx.quick),
         "post-layout": _figures(post, ctx.backend, ctx.jobs, ctx.quick)}
    s, p = f["schematic"], f["post-layout"]
    rows = []

    def row(label, get, scale, unit):
        for w in _ARR:
            a, b = get(s, w), get(p, w)
            rows.append([f"{label}, {w} ({unit})", a * scale, b * scale, (b / a - 1) * 100 if a else "-"])
    row("C_FD", lambda x, w: x[w]["c_fd_F"], 1e15, "fF")
    row("C_PD,node", lambda x, w: x[w]["c_pd_node_F"], 1e15, "fF")
    row(N.cg_node(d.pixel.v_pd_reset), lambda x, w: Q / x[w]["c_pd_node_F"], 1e6, "uV/e-")
    row("CG_FD", lambda x, w: x[w]["cg_fd_V_per_e"], 1e6, "uV/e-")
    row("CG_out(0), analytic", lambda x, w: x[w]["cg_out_V_per_e"], 1e6, "uV/e-")
    row("CG_out(0), SPICE charge step", lambda x, w: x[w]["cg_out_spice_V_per_e"], 1e6, "uV/e-")
    row("read noise at the column", lambda x, w: x[w]["read_noise_e"], 1.0, "e-")
    row(N.fw_jdep_cv(d.tech.photodiode.reset_bias), lambda x, w: x[w]["full_well_e"], 1e-3, "ke-")
    for key, label, scale, unit in (("col_to_col", "column-to-column crosstalk (secondary / primary signal)", 100, "%"),
                                    ("pedestal_p_V", "pedestal, primary (row lines into FD)", 1e3, "mV"),
                                    ("pedestal_s_V", "pedestal, secondary (row lines into FD)", 1e3, "mV")):
        a, b = s["crosstalk"][key], p["crosstalk"][key]
        rows.append([f"{label} ({unit})", a * scale, b * scale, (b / a - 1) * 100 if a else "-"])
    rows.append(["AFE gain error, SPICE (%)", s["afe_gain_error"] * 100, p["afe_gain_error"] * 100, "-"])
    for w in _ARR:
        a, b = s["settling_V"][w], p["settling_V"][w]
        rows.append([f"AFE settling error at f_read = {getattr(d, w).f_read / 1e3:g} kHz, {w} (mV)", a * 1e3, b * 1e3,
                     (b / a - 1) * 100 if a else "-"])
    if "sized" in s:
        for key, label, scale in (("c_m", "sized C_M", 1.0), ("mask_open_m2", "sized mask opening (um2)", 1e12),
                                  ("t_int_primary_s", "sized t_int, primary (us)", 1e6),
                                  ("t_int_secondary_s", "sized t_int, secondary (us)", 1e6)):
            a, b = s["sized"][key] * scale, p["sized"][key] * scale
            rows.append([f"{label} ({s['sized']['level']} level)", a, b, (b / a - 1) * 100])
    if not ctx.quick:
        for key, label in (("i_mid_A", "i_mid, primary"), ("i_5pct_A", "i_5pct, secondary")):
            rows.append([f"{label} (pA)", s[key] * 1e12, p[key] * 1e12, (p[key] / s[key] - 1) * 100])
    pl = post.post_layout
    wiring = []
    for w in _ARR:
        col = "col_p" if w == "primary" else "col_s0"
        coupled = sum(c for a, b, c in pl.column_pairs if col in (a, b))
        wiring.append([w, pl.node_wiring(w, "fd", p["a_sf"]) * 1e15, pl.node_wiring(w, "pd") * 1e15,
                       (pl.column_cap[w] + pl.per_row[col]) * 1e15, coupled * 1e15])
    res = [[k, v] for k, v in pl.resistance.items()]
    mvs = max(abs(p[w]["cg_out_V_per_e"] / p[w]["cg_out_spice_V_per_e"] - 1) for w in _ARR)
    text = [f"The design's dual pixel and column circuits drawn, extracted ({pl.source}) and placed in its netlists "
            "(docs/post-layout.md); every figure computed on both views. The analytic figures take the extracted "
            "capacitances; the SPICE figures run the post-layout netlists.",
            f"Post-layout, the analytic CG_out(0) is within {mvs * 100:.2f} % of the SPICE charge step.",
            "Row-to-FD: the pedestal (zero-light column signal) moves with the row lines' couplings into FD: RS "
            "rises before the signal sample and kicks FD by C(fd, rs) / C_FD x the RS swing, while the reset level, "
            "sampled after FD's reset with RS held, is not kicked. Column-to-column: the lines are driven by their "
            "source followers while they are sampled, so a coupling's step has settled by the sample.",
            "Settling error at f_read: the AFE output of a column's second row read at f_read minus the same read "
            "10 x slower (the verify figure). The sizing (casadi) runs on each view's curves: the analytic level in "
            "the quick profile, the design's level in the full one. The AFE's wiring (the drawn AFE_P / AFE_S, "
            "their mean) is in the post-layout SC stage. The 2 x 2 frame (fig. 3.13 of [Thesis2019]): the report's "
            "array frame, one deck with every column's AFE, on both views."]
    frame_rows = [[k, r, j, i * 1e12, a * 1e3, b * 1e3, (b - a) * 1e3, oa, ob, (ob - oa) * 1e3]
                  for (k, r, j, i, a, oa), (*_, b, ob) in zip(s["frame"], p["frame"])]
    fig = _frame_figure(ctx, frame_rows)
    worst = max(abs(x[6]) for x in frame_rows)
    text.append(f"In the 2 x 2 frame the post-layout signals differ from the schematic's by {worst:.1f} mV at most.")
    if ctx.quick:
        text.append("Quick profile: i_mid / i_5pct (the SPICE sweeps of the experiment) are left to the full report.")
    return Section(
        TITLE, text=text,
        tables=[Table("post_layout_vs_schematic", "Schematic vs post-layout",
                      ["figure", "schematic", "post-layout", "change (%)"], rows),
                Table("post_layout_wiring", "Extracted wiring on the pixel's nodes",
                      ["subpixel", "FD wiring, SF-bootstrapped (fF)", "PD wiring (fF)",
                       "column line to ground and quiet lines, all rows (fF)",
                       "column line to the other column lines, all rows (fF)"],
                      wiring),
                Table("post_layout_resistance", "Long lines: end-to-end resistance", ["line", "R (Ohm)"], res),
                Table("post_layout_frame", "The 2 x 2 frame with its AFEs (fig. 3.13), schematic vs post-layout",
                      ["array", "row", "column", "photocurrent (pA)", "signal, schematic (mV)",
                       "signal, post-layout (mV)", "change (mV)", "AFE out, schematic (V)", "AFE out, post-layout (V)",
                       "AFE change (mV)"], frame_rows)],
        figures=[Figure(fig.name, "The 2 x 2 frame's double-sampled signals, schematic and post-layout (fig. 3.13)")],
        checked=[Checked("post_layout.cg_model_vs_spice_frac", mvs, "1", tol_abs=0.005,
                         note="post-layout CG_out(0), analytic vs SPICE charge step"),
                 *(Checked(f"post_layout.c_fd_{w}_F", p[w]["c_fd_F"], "F", tol_rel=0.02) for w in _ARR)],
        data=f)
