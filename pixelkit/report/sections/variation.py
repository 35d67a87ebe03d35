"""Report section: process corners (a sweep) and Monte Carlo mismatch (fixed-pattern figures)."""
from __future__ import annotations

import numpy as np

from .. import names as N
from . import Checked, Figure, Section, Table

TITLE = "Sweeps, corners and Monte Carlo"


def build(ctx) -> Section:
    from ...mc.montecarlo import run_monte_carlo
    from ...sweep.run import run_sweep
    from ...sweep.space import parse_axis
    d = ctx.design
    corners = sorted(d.tech.models.corners)
    if ctx.quick:
        corners = [c for c in corners if c in ("tt", "ss", "ff")] or corners[:3]
    ctx.progress("corners", 0, 2)
    sw = run_sweep(d, [parse_axis("corner=" + ",".join(corners))], backend=ctx.backend, jobs=ctx.jobs)
    rows_c = [[p["corner"], *(None if p[f] is None else round(p[f] * 1e3, 3) for f in
                              ("signal_primary_V", "signal_secondary_V", "reset_primary_V", "reset_secondary_V")),
               p["message"] or ("ok" if p["ok"] else "failed")] for p in sw.points]
    ctx.progress("Monte Carlo", 1, 2)
    size = (2, 2) if ctx.quick else (6, 4)
    mc = run_monte_carlo(d, *size, seed=1, backend=ctx.backend, jobs=ctx.jobs)
    fig = ctx.figure("variation_offsets.png")
    _plot(mc, fig)
    rows_m = []
    for k in ("primary", "secondary"):
        r = mc[k]
        rows_m.append([k, round(r["pedestal_V"] * 1e3, 3), round(r["dsnu_V"] * 1e3, 4), round(r["prnu_pct"], 3),
                       round(r["column_fpn_V"] * 1e3, 4), round(r["offset_fpn_V"] * 1e3, 3)])
    p = mc["pelgrom"]
    nominal = ctx.experiment()["secondary"]["pedestal_V"]
    text = [
        f"Corners: the dual-pixel bench at half the primary's swing and 5 % of the secondary's, one "
        f"point per model corner ({', '.join(corners)}), through `pixelkit sweep --over corner=...`.",
        f"Monte Carlo: one chip (seed 1) of {size[0]} x {size[1]} dual pixels with the GF180 models' own "
        "per-device threshold and current-factor mismatch (sw_stat_mismatch = 1), dark and under a "
        "uniform field at 50 % of the primary's full scale (`pixelkit mc`).",
        f"Independent check: the offset FPN before double sampling, {p['measured_offset_fpn_V'] * 1e3:.2f} mV "
        f"measured over {p['samples']} pixels, against the Pelgrom estimate G_SF sigma_VT(SF) = "
        f"{p['sf_gain']:.3f} x {p['sigma_vth_sf_V'] * 1e3:.2f} mV = {p['sigma_reset_V'] * 1e3:.2f} mV "
        f"(ratio {p['ratio']:.2f}; the test accepts 0.8 - 1.3).",
        f"The secondary's 5 % target is {mc['secondary']['target_over_dsnu']:.0f} x its dark-signal spread "
        f"(DSNU, Monte Carlo {mc['secondary']['dsnu_V'] * 1e3:.2f} mV).",
        f"The pedestal here is the mean over the Monte Carlo chip's dark frame ({mc['secondary']['pedestal_V'] * 1e3:.2f} "
        f"mV, secondary): the nominal pixel's pedestal of the simulation experiment is "
        f"{nominal * 1e3:.2f} mV; they differ by the drawn mismatch and the array frame's bench (another deck and "
        "row timing), not by definition of the pedestal.",
        "DSNU, Monte Carlo draws every device of the chip from the GF180 statistical models and measures the dark "
        "frame after double sampling; the virtual camera's DSNU, model counts only the TG channel charge.",
    ]
    return Section(
        TITLE, text=text,
        tables=[Table("variation_corners", "Process corners (mV)",
                      ["corner", "primary signal (mV)", "secondary signal (mV)", "primary reset level (mV)",
                       "secondary reset level (mV)", "status"], rows_c),
                Table("variation_fpn", "Monte Carlo fixed-pattern figures (one chip)",
                      ["array", "pedestal, mean over the chip (mV)", N.label("DSNU, Monte Carlo"), "PRNU (%)",
                       "column FPN (mV)", "offset FPN before DS (mV)"], rows_m)],
        figures=[Figure(fig.name, "Column reset level (offset before double sampling) of every Monte Carlo "
                                  "pixel, deviation from its column's mean, with the Pelgrom Gaussian")],
        checked=[Checked("variation.secondary_pedestal_V", mc["secondary"]["pedestal_V"], "V", tol_abs=2e-3),
                 Checked("variation.offset_fpn_ratio", p["ratio"], "1", tol_abs=0.3)],
        data={"corners": sw.points, "monte_carlo": {k: v for k, v in mc.items()}})


def _plot(mc, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    dev = np.concatenate([np.asarray(mc[k]["reset_level_V"]) - np.asarray(mc[k]["reset_level_V"]).mean(axis=0)
                          for k in ("primary", "secondary")], axis=1).ravel() * 1e3
    s = mc["pelgrom"]["sigma_reset_V"] * 1e3
    fig, ax = plt.subplots(figsize=(5, 3))
    ax.hist(dev, bins=15, density=True, alpha=0.6, label="Monte Carlo")
    x = np.linspace(-4 * s, 4 * s, 200)
    ax.plot(x, np.exp(-0.5 * (x / s) ** 2) / (s * np.sqrt(2 * np.pi)), label=f"Pelgrom, sigma {s:.2f} mV")
    ax.set_xlabel("reset level - column mean (mV)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
