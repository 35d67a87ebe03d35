"""Other pixel families: the WDR pixel and the ratio pixel at their reference designs.

Independent paths: for the WDR pixel, the photocurrents of the transistor-level
deck against the decoder that only sees the stored voltages, and the knee / DR
against the closed-form charge model; for the ratio pixel, the loop's output
currents against the photocurrent ratio and the inverter trip times against the
interval law derived in ``families/ratio/law.py`` (tau from the uniform pair only).
The families do not depend on the report's design: they run at
``designs/wdr_pixel.toml`` and ``designs/ratio_pixel.toml``.
"""
from __future__ import annotations

import numpy as np

from ...families.goldens import DESIGNS
from ...families.ratio.design import load_ratio_design
from ...families.ratio.experiment import run_ratio_experiment
from ...families.ratio.law import interval_over_tau
from ...families.wdr.design import load_wdr_design
from ...families.wdr.experiment import run_wdr_experiment
from . import Checked, Figure, Section, Table

TITLE = "Other pixel families: WDR and ratio pixels"


def _wdr_figure(ctx, w):
    from ..figures import axes, save
    fig, (a, b) = axes(2, 9, 3.4)
    rows = w["sweep"]
    i = np.array([r["i_true_A"] for r in rows])
    dec = np.array([r["i_decoded_A"] for r in rows])
    hi = np.array([r["regime"] == "high" for r in rows])
    a.loglog(i, i, "k-", lw=0.8, label="truth")
    a.loglog(i[~hi], dec[~hi], "o", label="decoded: signal 3 (fixed exposure)")
    a.loglog(i[hi], dec[hi], "s", label="decoded: t_c from signal 1/2")
    a.axvline(w["knee"]["i_knee_model_A"], color="C3", ls="--", lw=0.8, label="knee (V0, model)")
    a.set_xlabel("photocurrent (A)")
    a.set_ylabel("decoded (A)")
    a.legend(fontsize=7)
    b.semilogx(i, 100 * np.array([r["err_frac"] for r in rows]), "o-")
    b.set_xlabel("photocurrent (A)")
    b.set_ylabel("decoding error (%)")
    path = save(fig, ctx.figure("families_wdr_decode.png"))
    return Figure(path.name, "WDR pixel: decoded against true photocurrent over "
                             f"{w['decades']:.1f} decades (SPICE), and the relative error")


def _ratio_figure(ctx, r):
    from ..figures import axes, save
    fig, (a, b) = axes(2, 9, 3.4)
    rf = np.geomspace(1, 32, 100)
    a.plot(rf, interval_over_tau(rf), "k-", lw=0.8, label="law: R_F - 1/R_F")
    for bias, mark in zip(r["biases"], "os"):
        cells = [c for c in bias["cells"] if c["role"] == "ratio"]
        x = [max(c["rf"], 1 / c["rf"]) for c in cells]
        a.plot(x, [abs(c["interval_over_tau"]) for c in cells], mark,
               label=f"SPICE, I_bias = {bias['i_bias_A'] * 1e9:g} nA")
        lv = bias["intensity_sweep"]
        b.semilogx([q["total_A"] for q in lv], [100 * q["err_frac"] for q in lv], mark + "-",
                   label=f"I_bias = {bias['i_bias_A'] * 1e9:g} nA")
    a.set_xlabel("photocurrent ratio R_F")
    a.set_ylabel("counter interval / tau")
    a.legend(fontsize=7)
    b.set_xlabel("pair photocurrent (A), R_F = 10")
    b.set_ylabel("output-ratio error (%)")
    b.legend(fontsize=7)
    path = save(fig, ctx.figure("families_ratio_law.png"))
    return Figure(path.name, "Ratio pixel: counter interval against the derived law (tau from the 1:1 pair), "
                             "and the loop's ratio error against the light level at both biases")


def build(ctx) -> Section:
    if not all((DESIGNS / f).is_file() for f in ("wdr_pixel.toml", "ratio_pixel.toml")):
        return Section.unavailable(TITLE, f"the reference designs wdr_pixel.toml and ratio_pixel.toml are not in "
                                          f"{DESIGNS} (an installed package without the repository)")
    wd = load_wdr_design(DESIGNS / "wdr_pixel.toml")
    rd = load_ratio_design(DESIGNS / "ratio_pixel.toml")
    ctx.progress("families: WDR pixel")
    w = run_wdr_experiment(wd, backend=ctx.backend, jobs=ctx.jobs)
    ctx.progress("families: ratio pixel")
    r = run_ratio_experiment(rd, backend=ctx.backend, jobs=ctx.jobs)
    hb = r["high_bias"]
    text = [
        f"WDR pixel ({wd.name}): {len(w['sweep'])} photocurrents over {w['decades']:.1f} decades in one deck "
        "(and two around the knee at a second V0); "
        f"worst decoding error {100 * w['decode_max_err_frac']:.1f} %. Simulated DR {w['dr_db']:.1f} dB "
        f"against CVDR + 20 log10(2^N) = {w['cvdr_db']:.1f} + {w['dr_steps_db']:.1f} = "
        f"{w['dr_formula_db']:.1f} dB (paper: 112 dB expected, ~100 dB measured).",
        f"Ratio pixel ({rd.name}): at {r['i_bias_A'] * 1e9:g} nA the loop's output ratio follows the "
        f"photocurrent ratio (1:1 - 1:30) within {100 * r['ratio_law_max_err_frac']:.1f} %, the counter "
        f"interval follows tau (R_F - 1/R_F) within {100 * r['interval_law_max_err_frac']:.1f} %. At "
        f"{hb['i_bias_A'] * 1e9:g} nA the same scene is off by {100 * hb['ratio_law_max_err_frac']:.0f} % "
        "and the error depends on the light level.",
    ]
    wdr_rows = [[r_["i_true_A"], r_["i_decoded_A"], 100 * r_["err_frac"], r_["regime"],
                 "" if r_["t_c_decoded_s"] is None else r_["t_c_decoded_s"] * 1e6] for r_ in w["sweep"]]
    ratio_rows = [[b["i_bias_A"] * 1e9, c["role"], c["rf"], c["total_A"], c["out_ratio"], 100 * c["ratio_err_frac"],
                   c["interval_over_tau"], c["law_over_tau"], c["count"]]
                  for b in r["biases"] for c in b["cells"]]
    return Section(
        TITLE, text=text,
        tables=[Table("families_wdr_sweep", "WDR pixel: truth, decoded intensity, regime, t_c",
                      ["I true (A)", "I decoded (A)", "error (%)", "regime", "t_c (us)"], wdr_rows),
                Table("families_ratio_cells", "Ratio pixel: every pair of both benches",
                      ["I_bias (nA)", "role", "R_F", "pair total (A)", "I_out-/I_out+", "error (%)",
                       "T/tau (SPICE)", "T/tau (law)", "count"], ratio_rows)],
        figures=[_wdr_figure(ctx, w), _ratio_figure(ctx, r)],
        checked=[Checked("families.wdr_decode_max_err_frac", w["decode_max_err_frac"], "1", tol_abs=0.01),
                 Checked("families.wdr_dr_db", w["dr_db"], "dB", tol_abs=0.5),
                 Checked("families.ratio_law_max_err_frac", r["ratio_law_max_err_frac"], "1", tol_abs=0.005),
                 Checked("families.ratio_interval_law_max_err_frac", r["interval_law_max_err_frac"], "1",
                         tol_abs=0.005),
                 Checked("families.ratio_rf_min", r["rf_min"], "1", tol_rel=1e-6),
                 Checked("families.ratio_dr_adj_db", r["dr_adj_db"], "dB", tol_abs=0.01)],
        data={"wdr": w, "ratio": r})
