"""The 2 x 2 integrated-pixel array read row by row (thesis fig. 3.13), sample phases marked.

Each subpixel gets its own photocurrent (as the thesis did) so every one is told
apart; the columns are plotted after the SF, before the AFE. Shaded: the S1
(signal) and S2 (reset level) sampling windows of each row, per array.
"""
from __future__ import annotations

from ...circuits.array import array_bench, frame_timings
from ...measure.pixel import double_sampled
from ...spice import simulate_many
from ..figures import axes, save
from . import Checked, Figure, Section, Table

TITLE = "2 x 2 array readout (fig. 3.13)"
ROWS = COLS = 2


def currents(n: int):
    """Distinct photocurrents: primary 0.2, 0.4, ... nA; secondary 10, 20, ... pA (as ``pixelkit array``)."""
    ip = [[0.2e-9 * (1 + r * COLS + c) for c in range(COLS)] for r in range(ROWS)]
    is_ = [[10e-12 * (1 + r * n * COLS + j) for j in range(n * COLS)] for r in range(ROWS)]
    return ip, is_


def build(ctx) -> Section:
    d = ctx.design
    n = d.secondary_per_pixel
    ip, is_ = currents(n)
    ctx.progress("array", 0, 1)
    res = simulate_many([array_bench(d, ip, is_, title="report_array")], backend=ctx.backend, jobs=1)[0]
    tm = frame_timings(d, d.experiment.t_window, ROWS)
    groups = {"primary": [f"col_p_{c}" for c in range(COLS)], "secondary": [f"col_s_{j}" for j in range(n * COLS)]}
    fig, _ = axes(1, 9, 1)
    fig.clf()
    axs = fig.subplots(2, 1, sharex=True)
    fig.set_size_inches(9, 5.6)
    t_us = res.time * 1e6
    rows = []
    for ax, (w, cols) in zip(axs, groups.items()):
        t = tm[w]
        for r in range(ROWS):
            for k, (lo, hi) in enumerate((t.s1_window(r), t.s2_window(r))):
                ax.axvspan(lo * 1e6, hi * 1e6, color="C2" if k == 0 else "C4", alpha=0.15, lw=0,
                           label=("S1 (signal)" if k == 0 else "S2 (reset level)") if r == 0 else None)
        for node in cols:
            ax.plot(t_us, res[node], lw=0.8, label=node)
        ax.set_ylabel(f"{w} column (V)")
        ax.legend(fontsize=6, ncol=5, loc="lower left")
        for r in range(ROWS):
            for c, node in enumerate(cols):
                cur = (ip if w == "primary" else is_)[r][c]
                rows.append([w, r, c, cur * 1e12, double_sampled(res, node, t, r) * 1e3])
    axs[0].set_xlim(min(x.t_read for x in tm.values()) * 1e6 - 1, max(x.t_stop for x in tm.values()) * 1e6)
    axs[-1].set_xlabel("time (us)")
    axs[0].set_title(f"{d.name}: {ROWS} x {COLS} readout after the SF, before the AFE; shaded: sample phases")
    path = save(fig, ctx.figure("array_readout.png"))
    checked = [Checked(f"array.{w}_r{r}c{c}_V", s * 1e-3, "V", 0.0, 2e-3) for w, r, c, _, s in rows]
    return Section(TITLE, text=[f"Exposure {d.experiment.t_window * 1e6:g} us (global shutter), then row by row: "
                                f"primary at {d.primary.f_read * 1e-3:g} kHz, secondary at "
                                f"{d.secondary.f_read * 1e-3:g} kHz. The double-sampled signal of each subpixel "
                                "(reset level at S2 minus signal level at S1) is in the table."],
                   figures=[Figure(path.name, "2 x 2 array readout waveforms with the S1 / S2 sample phases (fig. 3.13)")],
                   tables=[Table("array_signals", "Double-sampled signal per subpixel",
                                 ["array", "row", "column", "photocurrent (pA)", "signal (mV)"], rows)],
                   checked=checked)
