"""Design summary: the design's key figures, each under one name (``report.names``).

Kit values: the analytic PD-referred figures (``physics.subpixel``), the output-referred
conversion gain at zero signal from the physics (``physics.fd.response`` at the design's PD
reset level, A_sf from the SF's SPICE operating point), and the output-referred gain
*measured in SPICE*: the slope of the double-sampled column signal against the collected
charge I t_window over 0 - 30 % of the column swing of the simulation experiment's sweep.
For the test chip of [Thesis2019] (``ctx.reference``) the dissertation's table 3.2 and
sizing values stand beside the kit's, as a validation; for any other design they do not
appear. The glossary table names every figure that has more than one definition.
"""
from __future__ import annotations

import numpy as np

from ...camera.spicenoise import sf_gain
from ...constants import Q
from ...experiments.reference import THESIS, departures
from ...physics.subpixel import model_table
from .. import names as N
from . import Checked, Section, Table

TITLE = "Design summary"


def spice_output_cg(sweep_A, signal_V, dark_V: float, swing_V: float, t_window: float) -> float:
    """Slope of the column signal against the collected charge (V/e-) below 30 % of swing."""
    i, s = np.asarray(sweep_A), np.asarray(signal_V)
    ok = (s - dark_V) <= 0.3 * swing_V
    slope = np.polyfit(i[ok] * t_window / Q, s[ok], 1)[0]
    return float(slope)


def build(ctx) -> Section:
    d = ctx.design
    from ...techfit.ekv import models_for
    mt = model_table(d, sf_gain(d), models_for(d))
    exp = ctx.experiment()
    kit, out_cg, spice_cg = {}, {}, {}
    for w in ("primary", "secondary"):
        kit[w] = mt[w]
        out_cg[w] = mt[w]["at_reset"]["cg_out_V_per_e"]
        e = exp[w]
        spice_cg[w] = spice_output_cg(e["sweep_A"], e["signal_V"], e["pedestal_V"], e["swing_V"], exp["t_window_s"])
    th = {w: {k: (f"{v:g}" if isinstance(v, float) else v) for k, v in THESIS[w].items()}   # as printed
          for w in ("primary", "secondary")}
    thr = {k: f"{v:g}" for k, v in THESIS.items() if isinstance(v, float)}
    p, s = d.primary, d.secondary
    v_r, v_reset = mt["reset_bias_V"], d.pixel.v_pd_reset
    mask = ["unmasked" if x.mask_opening is None else x.mask_opening * 1e12 for x in (p, s)]
    # (label, thesis primary, kit primary, thesis secondary, kit secondary)
    rows = [
        ["array (rows x cols)", th["primary"]["array"], f"{p.rows} x {p.cols}", th["secondary"]["array"],
         f"{s.rows} x {s.cols}"],
        ["pixel pitch (um)", th["primary"]["pitch_um"], p.pitch * 1e6, th["secondary"]["pitch_um"], s.pitch * 1e6],
        ["PD (um x um)", th["primary"]["pd"], f"{p.pd_width * 1e6:g} x {p.pd_height * 1e6:g}", th["secondary"]["pd"],
         f"{s.pd_width * 1e6:g} x {s.pd_height * 1e6:g}"],
        [N.label(N.c_jdep(v_r)), th["primary"]["c_jdep_fF"], kit["primary"]["c_jdep_F"] * 1e15,
         th["secondary"]["c_jdep_fF"], kit["secondary"]["c_jdep_F"] * 1e15],
        [N.label(N.c_node(v_r)), "-", kit["primary"]["c_node_F"] * 1e15, "-", kit["secondary"]["c_node_F"] * 1e15],
        [N.label(N.cg_jdep(v_r)), th["primary"]["cg_uV"], kit["primary"]["cg_V_per_e"] * 1e6, th["secondary"]["cg_uV"],
         kit["secondary"]["cg_V_per_e"] * 1e6],
        [N.label(N.cg_node(v_reset)), "-", Q / kit["primary"]["at_reset"]["c_pd_node_F"] * 1e6, "-",
         Q / kit["secondary"]["at_reset"]["c_pd_node_F"] * 1e6],
        [N.label("CG_out(0)"), "-", out_cg["primary"] * 1e6, "-", out_cg["secondary"] * 1e6],
        [N.label("CG_out(0-30 %)"), "-", spice_cg["primary"] * 1e6, "-", spice_cg["secondary"] * 1e6],
        [N.label(N.fw_jdep(v_r)), th["primary"]["fwc_ke"], kit["primary"]["fwc_e"] * 1e-3,
         th["secondary"]["fwc_ke"], kit["secondary"]["fwc_e"] * 1e-3],
        [N.label(N.fw_jdep_cv(v_r)), "-", kit["primary"]["fwc_cv_e"] * 1e-3, "-", kit["secondary"]["fwc_cv_e"] * 1e-3],
        ["pixel swing (V)", th["primary"]["swing_V"], d.pixel.swing, th["secondary"]["swing_V"], d.pixel.swing],
        ["column swing, SPICE (V)", "-", exp["primary"]["swing_V"], "-", exp["secondary"]["swing_V"]],
        ["readout clock (kHz)", th["primary"]["f_read_kHz"], p.f_read * 1e-3, th["secondary"]["f_read_kHz"],
         s.f_read * 1e-3],
        ["mask opening (um2)", "-", mask[0], th["secondary"]["mask_um2"], mask[1]],
    ]
    ratios = [
        ["C_A = A1 / A2", thr["c_a"], mt["c_a"]],
        [f"C_C = C_jdep1 / C_jdep2 at {v_r:g} V", thr["c_c"], mt["c_c"]],
        ["primary photocurrent at mid-scale (pA)", thr["i_mid_pA"], exp["primary"]["i_mid_A"] * 1e12],
        ["secondary photocurrent at 5 % (pA)", thr["i_5pct_pA"], exp["secondary"]["i_5pct_A"] * 1e12],
        ["i_mid / i_5pct", f"{THESIS['i_mid_pA']:g} / {THESIS['i_5pct_pA']:g}", exp["ratio"]],
    ]
    drop = 100 * (1 - spice_cg["primary"] / out_cg["primary"])
    text = [f"{d.name} (revision {d.revision}) in technology {d.tech.name}. The PD-referred figures are the "
            f"analytic junction model at {v_r:g} V reverse bias, the technology's reference bias (eq. 3.5, 3.6 of "
            "[Thesis2019]); the output-referred gains are the model's at zero signal and a SPICE measurement over "
            "the first 30 % of the swing (independent of the analytic model: it includes FD charge sharing and "
            "the SF gain).",
            "Two output-referred gains, two definitions: CG_out(0) is the small-signal gain at the "
            f"{v_reset:g} V PD reset level; CG_out(0-30 %) the mean slope over 0 - 30 % of the "
            f"swing, {drop:.1f} % lower for the primary because the node's C(V) grows as it discharges. The "
            f"Noise section's {N.cg_jdep(v_reset)} is the same junction as {N.cg_jdep(v_r)} at the design's "
            f"{v_reset:g} V PD reset instead of {v_r:g} V (a lower reverse bias: a larger C_jdep)."]
    if ctx.reference:
        text.append("This design is the test chip of [Thesis2019]: its columns give the dissertation's table 3.2 "
                    "and sizing values beside the kit's, as a validation of the kit.")
        text += [f"It departs from the dissertation in {x}." for x in departures(d)]
        tables = [Table("design_summary", "Key figures: [Thesis2019] table 3.2 beside the kit",
                        ["figure", "[Thesis2019] primary", "kit primary", "[Thesis2019] secondary", "kit secondary"],
                        rows),
                  Table("design_ratios", "Sizing ratios: [Thesis2019] beside the kit",
                        ["ratio", "[Thesis2019]", "kit"], ratios)]
    else:
        tables = [Table("design_summary", "Key figures", ["figure", "primary", "secondary"],
                        [[r[0], r[2], r[4]] for r in rows]),
                  Table("design_ratios", "Sizing ratios", ["ratio", "value"], [[r[0], r[2]] for r in ratios])]
    tables.append(Table("figure_names", "Names of the figures that have more than one definition (used "
                        "throughout this report, and by the sign-off's figures), and why each is kept",
                        N.GLOSSARY_COLUMNS,
                        N.glossary_rows([N.c_jdep(v_r), N.c_node(v_r), N.cg_jdep(v_r), N.cg_jdep(v_reset),
                                         N.cg_node(v_reset), "CG_out(0)", "CG_out(0-30 %)", "K x LSB",
                                         N.fw_jdep(v_r), N.fw_jdep_cv(v_r), "full well at the column",
                                         "mu_e.sat (EMVA)", "read noise at the column", "read noise with the AFE",
                                         "sigma_d (EMVA)", "pedestal", "DSNU, model", "DSNU, Monte Carlo"])))
    checked = []
    for w in ("primary", "secondary"):
        checked += [
            Checked(f"summary.{w}.cg_jdep_uV_per_e", kit[w]["cg_V_per_e"] * 1e6, "uV/e-", 0.005, 0.0,
                    N.cg_jdep(v_r)),
            Checked(f"summary.{w}.cg_out_0_30_uV_per_e", spice_cg[w] * 1e6, "uV/e-", 0.02, 0.0, "CG_out(0-30 %)"),
            Checked(f"summary.{w}.fwc_ke", kit[w]["fwc_e"] * 1e-3, "ke-", 0.005, 0.0, N.fw_jdep(v_r)),
            Checked(f"summary.{w}.cg_out_0_uV_per_e", out_cg[w] * 1e6, "uV/e-", 0.01, 0.0, "CG_out(0)"),
        ]
    checked += [Checked("summary.c_a", mt["c_a"], "1", 0.002), Checked("summary.c_c", mt["c_c"], "1", 0.005)]
    return Section(TITLE, text=text, tables=tables, checked=checked,
                   data={"model_table": mt, "spice_output_cg_V_per_e": spice_cg,
                         "physics_output_cg_V_per_e": out_cg, "reference": ctx.reference,
                         **({"thesis": THESIS} if ctx.reference else {})})
