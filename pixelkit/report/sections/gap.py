"""Sim-to-real diagnosis (``--measured M.csv``): where the measured data leave the nominal model,
which silicon effect explains the gap, and whether it is explained (``gap.diagnose.analyse``).

Independent path: the measured data themselves against the SPICE-calibrated surrogate of the
design (its own error against full-chain SPICE is stated); the held-out rows judge the fit.
The gap package's HTML section (``gap/report.py``, with its residual heatmaps) is written beside
the report and its heatmaps are shown here.
"""
from __future__ import annotations

from . import Checked, Figure, Section, Table

TITLE = "Sim-to-real diagnosis (--measured)"


def build(ctx) -> Section:
    if ctx.measured is None:
        return Section.needs_input(TITLE, "--measured", "M.csv, measured data in the gap table format of "
                                   "pixelkit gap diagnose: adds the sim-to-real diagnosis")
    from ...gap.data import read_table
    from ...gap.diagnose import analyse
    from ...gap.store import load_nominal
    from ...gap.report import write_section
    d = ctx.design
    table = read_table(ctx.measured, d, measured=True)
    ctx.progress("gap: SPICE-calibrated surrogate of the design")
    nom = load_nominal(d, backend=ctx.backend)
    ctx.progress("gap: fitting the candidate effects")
    r, X, resid = analyse(d, table, nom)
    html = write_section(r, d.name, X, resid, ctx.out_dir)
    images = sorted(p.name for p in ctx.out_dir.glob("gap_heatmap_*.png"))
    noise = f"{r['noise_rms_V'] * 1e3:.2f} mV ({r['noise_source']})" if r["noise_rms_V"] else "unknown"
    text = [f"{r['n_rows']} measured rows from {ctx.measured.name} ({r['n_train']} fitted, {r['n_heldout']} held "
            f"out), against the design's SPICE-calibrated surrogate (its error against full-chain SPICE: pixel "
            f"{r['surrogate_error']['pixel_max_V'] * 1e3:.2f} mV, AFE {r['surrogate_error']['afe_max_V'] * 1e3:.2f}"
            " mV at worst).",
            f"Verdict: {r['verdict']}",
            f"Best explanation: {r['best']}; held-out gap {r['gap_before_rms_V'] * 1e3:.2f} mV rms before, "
            f"{r['gap_after_rms_V'] * 1e3:.2f} mV after (shrink {r['shrink_frac'] * 100:.0f} %); measurement "
            f"noise {noise}. The gap package's own section: {html.name}."]
    ranking = [[x["effect"], x["heldout_rms_V"] * 1e3, x["bic"], "yes" if x.get("beats_none") else "no"]
               for x in r["ranking"]]
    where = [[w["factor"], str(w["level"]), w["n"], w["mean_V"] * 1e3, w["p"]] for w in r["where"][:20]]
    regions = [[g["region"], g["n"], g["rms_before_V"] * 1e3, g["rms_after_V"] * 1e3] for g in r["regions"]]
    tables = [Table("gap_ranking", "Candidate effects, ranked (held-out rms and BIC)",
                    ["effect", "held-out rms (mV)", "BIC", "beats 'none'"], ranking),
              Table("gap_where", "Where the data leave the nominal model (significant first)",
                    ["factor", "group", "n", "mean residual (mV)", "p"], where or [["-", "-", 0, 0.0, 1.0]])]
    if regions:
        tables.append(Table("gap_regions", "Held-out gap by region", ["region", "n", "rms before (mV)",
                                                                       "rms after (mV)"], regions))
    # the diagnosis of fixed data is deterministic (seeded split); 5 % / 0.05 mV covers the
    # surrogate's rebuild on another machine, a real change of the design moves the nominal by mV
    checked = [Checked("gap.gap_before_rms_V", r["gap_before_rms_V"], "V", tol_rel=0.05, tol_abs=5e-5),
               Checked("gap.gap_after_rms_V", r["gap_after_rms_V"], "V", tol_rel=0.05, tol_abs=5e-5)]
    return Section(TITLE, text=text, tables=tables, checked=checked, files=[html.name],
                   figures=[Figure(n, f"Mean residual against the nominal model, {n[12:-4]} array "
                                      "(row x column)") for n in images],
                   data={k: r[k] for k in ("best", "verdict", "explained", "indistinguishable", "shrink_frac",
                                           "gap_before_rms_V", "gap_after_rms_V", "noise_rms_V") if k in r})
