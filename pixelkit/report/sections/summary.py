"""Design summary in the form of the table 3.2 of [Thesis2019], the kit's values beside the thesis's.

Kit values: the analytic PD-referred figures (``physics.subpixel``), the
output-referred conversion gain from the physics (``physics.fd.response`` at the
design's reset bias, A_sf from the SF's SPICE operating point), and the
output-referred gain *measured in SPICE*: the slope
of the double-sampled column signal against the collected charge I t_window over
the linear part of the experiment's sweep (below 30 % of the column swing).
"""
from __future__ import annotations

import numpy as np

from ...camera.spicenoise import sf_gain
from ...constants import Q
from ...experiments.reference import THESIS
from ...physics.subpixel import model_table
from . import Checked, Section, Table

TITLE = "Design summary (thesis table 3.2)"


def spice_output_cg(sweep_A, signal_V, dark_V: float, swing_V: float, t_window: float) -> float:
    """Slope of the column signal against the collected charge (V/e-) below 30 % of swing."""
    i, s = np.asarray(sweep_A), np.asarray(signal_V)
    ok = (s - dark_V) <= 0.3 * swing_V
    slope = np.polyfit(i[ok] * t_window / Q, s[ok], 1)[0]
    return float(slope)


def build(ctx) -> Section:
    d = ctx.design
    mt = model_table(d, sf_gain(d))
    exp = ctx.experiment()
    kit, out_cg, spice_cg = {}, {}, {}
    out_src = "pixelkit.physics.fd.response (A_sf: camera.spicenoise.sf_gain)"
    for w, key in (("primary", "i_mid_A"), ("secondary", "i_5pct_A")):
        kit[w] = mt[w]
        out_cg[w] = mt[w]["at_reset"]["cg_out_V_per_e"]
        e = exp[w]
        spice_cg[w] = spice_output_cg(e["sweep_A"], e["signal_V"], e["dark_signal_V"], e["swing_V"], exp["t_window_s"])
    th = THESIS
    p, s = d.primary, d.secondary

    def cg_out(w):
        return round(out_cg[w] * 1e6, 3)

    rows = [
        ["array (rows x cols)", th["primary"]["array"], f"{p.rows} x {p.cols}", th["secondary"]["array"],
         f"{s.rows} x {s.cols}"],
        ["pixel pitch (um)", 24.0, p.pitch * 1e6, 8.0, s.pitch * 1e6],
        ["PD (um x um)", th["primary"]["pd"], f"{p.pd_width * 1e6:g} x {p.pd_height * 1e6:g}", th["secondary"]["pd"],
         f"{s.pd_width * 1e6:g} x {s.pd_height * 1e6:g}"],
        [f"C_jdep at V_R = {mt['reset_bias_V']:g} V (fF)", 26.54, kit["primary"]["c_jdep_F"] * 1e15, 7.38,
         kit["secondary"]["c_jdep_F"] * 1e15],
        ["PD node incl. EC/TG diffusions (fF)", "-", kit["primary"]["c_node_F"] * 1e15, "-",
         kit["secondary"]["c_node_F"] * 1e15],
        ["conversion gain, PD-referred q/C_jdep (uV/e-)", 6.03, kit["primary"]["cg_V_per_e"] * 1e6, 21.7,
         kit["secondary"]["cg_V_per_e"] * 1e6],
        ["conversion gain, output-referred, physics (uV/e-)", "-", cg_out("primary"), "-", cg_out("secondary")],
        ["conversion gain, output-referred, SPICE column (uV/e-)", "-", spice_cg["primary"] * 1e6, "-",
         spice_cg["secondary"] * 1e6],
        ["full well, swing x C (ke-)", 248.0, kit["primary"]["fwc_e"] * 1e-3, 69.0, kit["secondary"]["fwc_e"] * 1e-3],
        ["full well with C(V) (ke-)", "-", kit["primary"]["fwc_cv_e"] * 1e-3, "-", kit["secondary"]["fwc_cv_e"] * 1e-3],
        ["pixel swing (V)", 1.5, d.pixel.swing, 1.5, d.pixel.swing],
        ["column swing, SPICE (V)", "-", exp["primary"]["swing_V"], "-", exp["secondary"]["swing_V"]],
        ["readout clock (kHz)", 500.0, p.f_read * 1e-3, 1000.0, s.f_read * 1e-3],
        ["mask opening (um2)", "-", "unmasked" if p.mask_opening is None else p.mask_opening * 1e12, 0.64,
         "unmasked" if s.mask_opening is None else s.mask_opening * 1e12],
    ]
    ratios = [
        ["C_A = A1 / A2", th["c_a"], mt["c_a"]],
        ["C_C = C_jdep1 / C_jdep2", th["c_c"], mt["c_c"]],
        ["primary photocurrent at mid-scale (pA)", th["i_mid_pA"], exp["primary"]["i_mid_A"] * 1e12],
        ["secondary photocurrent at 5 % (pA)", th["i_5pct_pA"], exp["secondary"]["i_5pct_A"] * 1e12],
        ["i_mid / i_5pct", round(th["i_mid_pA"] / th["i_5pct_pA"], 2), exp["ratio"]],
    ]
    text = [f"{d.name} (revision {d.revision}) in technology {d.tech.name}. The thesis's columns are its table 3.2 "
            "and the values of its sizing text; the kit's PD-referred figures are the analytic model "
            "(eq. 3.5, 3.6), the output-referred gain measured in SPICE is the slope of the double-sampled column "
            "signal against the collected charge over the linear part of the experiment's sweep (independent of "
            "the analytic model: it includes FD charge sharing and the SF gain).",
            f"The output-referred gain from the physics model is from {out_src}."]
    checked = []
    for w in ("primary", "secondary"):
        checked += [
            Checked(f"summary.{w}.cg_pd_uV_per_e", kit[w]["cg_V_per_e"] * 1e6, "uV/e-", 0.005, 0.0, "analytic q/C_jdep"),
            Checked(f"summary.{w}.cg_out_spice_uV_per_e", spice_cg[w] * 1e6, "uV/e-", 0.02, 0.0,
                    "SPICE column signal per electron"),
            Checked(f"summary.{w}.fwc_ke", kit[w]["fwc_e"] * 1e-3, "ke-", 0.005, 0.0, "swing x C_jdep / q"),
        ]
        checked.append(Checked(f"summary.{w}.cg_out_physics_uV_per_e", out_cg[w] * 1e6, "uV/e-", 0.01, 0.0))
    checked += [Checked("summary.c_a", mt["c_a"], "1", 0.002), Checked("summary.c_c", mt["c_c"], "1", 0.005)]
    return Section(TITLE, text=text,
                   tables=[Table("design_summary", "Table 3.2 form: thesis vs kit",
                                 ["parameter", "thesis primary", "kit primary", "thesis secondary", "kit secondary"], rows),
                           Table("design_ratios", "Sizing ratios: thesis vs kit", ["ratio", "thesis", "kit"], ratios)],
                   checked=checked, data={"model_table": mt, "spice_output_cg_V_per_e": spice_cg,
                                          "physics_output_cg_V_per_e": out_cg, "thesis": THESIS})
