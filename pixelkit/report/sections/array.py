"""2 x 2 array readout ([Thesis2019] fig. 3.13): the column waveforms of one frame of both arrays with
the sample phases (S1 signal, RST, S2 reset level) marked, and the subpixel signals.

Independent path: each subpixel's double-sampled signal against the simulation experiment's
transfer curve (a different deck: one dual pixel and its column, ``experiments.thesis``) at the
same photocurrent and exposure window.
"""
from __future__ import annotations

import numpy as np

from ...chip.frame import STEPS_PER_ROW, simulate_frame
from ...chip.scene import default_map, photocurrents
from ...chip.settling import LONG_S1, describe, limits
from ...circuits.array import KINDS, PREFIX, array_bench, frame_timings
from ...measure.pixel import levels
from ...spice import simulate_many
from ..figures import axes, save
from . import Checked, Figure, Section, Table

TITLE = "2 x 2 array readout (fig. 3.13)"
ROWS = COLS = 2


def _plot(ctx, r, tm, n):
    fig, axs = axes(1, 10, 3.0)
    fig.clf()
    axs = fig.subplots(2, 1)
    fig.set_size_inches(10, 5.6)
    for ax, kind in zip(axs, KINDS):
        t = tm[kind]
        t0, t1 = t.row(0) - 0.1 * t.t_row, t.row(ROWS) + 0.05 * t.t_row
        m = (r.time >= t0) & (r.time <= t1)
        for j in range(COLS if kind == "primary" else n * COLS):
            node = f"col_{PREFIX[kind]}_{j}"
            ax.plot(r.time[m] * 1e6, r[node][m], lw=0.9, label=node)
            ax.plot(r.time[m] * 1e6, r[f"out_{node}"][m], lw=0.7, ls="--", label=f"AFE out {j}")
        for row in range(ROWS):
            for (a, b), c, lbl in ((t.s1_window(row), "C0", "S1"), (t.rst_window(row), "C3", "RST"),
                                   (t.s2_window(row), "C2", "S2")):
                ax.axvspan(a * 1e6, b * 1e6, color=c, alpha=0.12, lw=0, label=lbl if row == 0 else None)
        ax.set_ylabel("V")
        ax.set_title(f"{kind} array: columns (solid) and AFE outputs (dashed), rows read at "
                     f"{1 / t.t_row / 1e3:g} kHz", fontsize=9)
        ax.legend(fontsize=6, ncol=6, loc="lower left")
    axs[-1].set_xlabel("time (us)")
    path = save(fig, ctx.figure("array_readout.png"))
    return Figure(path.name, "2 x 2 frame, read-out phase: column voltages and AFE outputs with the sample "
                             "phases shaded (S1 signal sample, RST pulse, S2 reset sample), cf. [Thesis2019] fig. 3.13")


def frame(d, backend="batch", jobs=None, title=f"report_array_{ROWS}x{COLS}", options=None):
    """(SPICE result, frame timings, photocurrents) of the ``ROWS`` x ``COLS`` frame with the AFE under a
    left-to-right gradient, one deck (fig. 3.13 of [Thesis2019]); ``d`` may be a post-layout view;
    ``options``: simulator options over the defaults (``chip.frame.CONVERGED``)."""
    m, unit = default_map(ROWS, d.secondary_per_pixel * COLS, "gradient")
    ph = photocurrents(d, ROWS, COLS, m, unit)
    t_exp = d.experiment.t_window
    tm = frame_timings(d, t_exp, ROWS)
    step = min(t.t_row for t in tm.values()) / STEPS_PER_ROW
    net = array_bench(d, ph.iph_p, ph.iph_s, None, t_exp, True, None, step, title=title,
                      compression=ph.compression)
    (r,) = simulate_many([net], backend=backend, jobs=jobs, options=options)
    return r, tm, ph


def build(ctx) -> Section:
    d = ctx.design
    n = d.secondary_per_pixel
    t_exp = d.experiment.t_window
    ctx.progress("array: 2 x 2 frame with the AFE (one deck)", 0, 1)
    r, tm, ph = frame(d, ctx.backend, ctx.jobs)
    ctx.progress("array: 2 x 2 frame with the AFE (one deck)", 1, 1)
    ctx.progress("array: the same frame as column chains", 0, 1)
    split = simulate_frame(d, ph.iph_p, ph.iph_s, with_afe=True, split="columns", t_exp=t_exp,
                           backend=ctx.backend, jobs=ctx.jobs, settling=True, compression=ph.compression)
    settle = split.settling_summary(limits(d))
    ctx.progress("array: the same frame as column chains", 1, 1)
    exp = ctx.experiment()
    rows, checked, worst, worst_split = [], [], 0.0, 0.0
    for kind in KINDS:
        cur = ph.iph_p if kind == "primary" else ph.iph_s
        e = exp[kind]
        o = np.argsort(e["sweep_A"])
        i_curve, s_curve = np.asarray(e["sweep_A"])[o], np.asarray(e["signal_V"])[o]
        for row in range(ROWS):
            for j in range(cur.shape[1]):
                node = f"col_{PREFIX[kind]}_{j}"
                sig, rst = levels(r, node, tm[kind], row)
                afe = float(r.at(f"out_{node}", tm[kind].t_reset_level(row)))
                i = float(cur[row][j])
                dsplit = (rst - sig - float(split.signal[kind][row, j])) * 1e3
                worst_split = max(worst_split, abs(dsplit))
                inside = i_curve[0] <= i <= i_curve[-1]
                ref = float(np.interp(i, i_curve, s_curve)) if inside else None
                diff = (rst - sig - ref) * 1e3 if inside else None
                if diff is not None:
                    worst = max(worst, abs(diff))
                e = float(split.settling[kind][row, j])
                rows.append([kind, row, j, i * 1e12, rst, sig, (rst - sig) * 1e3, afe,
                             "-" if e != e else e * 1e3, dsplit,
                             "-" if ref is None else ref * 1e3, "-" if diff is None else diff])
                # 2 mV: the sampling-instant and settling resolution of one row (the experiment's
                # transfer interpolation adds less); a moved device size moves these by tens of mV
                checked.append(Checked(f"array.{kind}.r{row}c{j}.signal_V", rst - sig, "V", tol_abs=2e-3))
    checked.append(Checked("array.worst_split_vs_whole_mV", worst_split, "mV", tol_abs=0.5,
                           note="one deck vs column chains (a deck per row and column group, state handed over)"))
    worst_settle = max((v for v in settle["worst_V"].values() if v is not None), default=float("nan"))
    checked.append(Checked("array.settling_worst_mV", worst_settle * 1e3, "mV", tol_abs=0.2,
                           note="double-sampled signal vs the same read with long S1 and S2; limit "
                                + ", ".join(f"{k} {v * 1e3:g} mV" for k, v in settle["limit_V"].items())))
    fig = _plot(ctx, r, tm, n)
    text = [f"One {ROWS} x {COLS} frame of both arrays ({n} secondaries per dual pixel, so {n * COLS} secondary "
            f"columns) under a left-to-right gradient (5 - 80 % of the primary's full scale), simulated as one "
            f"deck with each column's load, S1X/S2X samplers and SC AFE, exposure {t_exp * 1e6:g} us, EC holding "
            "the PDs in reset while the rows wait. Each row: RS on, S1 samples the signal, RST resets FD, S2 "
            "samples the reset level (non-correlated double sampling, fig. 3.3).",
            f"Settling: every row is read a second time with S1 and S2 each held {LONG_S1} row times longer "
            f"(the same deck from the same column state); the double-sampled signal differs from that settled "
            f"read by at most {worst_settle * 1e3:.3f} mV (limits: "
            + ", ".join(f"{k} {v * 1e3:g} mV" for k, v in settle["limit_V"].items()) + "; "
            + ("within it" if not any(settle["beyond"].values()) else
               "BEYOND it: " + "; ".join(describe(settle))) + ", docs/timing-and-settling.md).",
            f"Checks: the same frame split into column chains (a deck per row and column group, the column "
            f"state handed over: the frame engine's fast path) agrees "
            f"with the one deck within {worst_split:.3f} mV. Against the simulation experiment's transfer curve "
            f"(one dual pixel and its column without the AFE, its own bench) at the same photocurrent the "
            f"frame's signals differ by at most {worst:.1f} mV: shown, not checked (the frame holds the PDs in "
            "reset while rows wait and its rows wait longer on FD)."]
    return Section(
        TITLE, text=text, figures=[fig], checked=checked,
        tables=[Table("array_signals", "Subpixel signals of the 2 x 2 frame",
                      ["array", "row", "column", "photocurrent (pA)", "reset level (V)", "signal level (V)",
                       "signal (mV)", "AFE out (V)", "settling error vs long S1 (mV)", "whole - split decks (mV)",
                       "experiment transfer (mV)", "difference to experiment (mV)"], rows)],
        data={"photocurrents": ph.as_dict(), "t_exp_s": t_exp})
