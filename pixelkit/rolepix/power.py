"""Power of the array read: the supply current of one column over a row read (its load's current
through the selected pixel's follower, the reset) and between rows (the bias mirror), from SPICE,
scaled to the array at the design's frame rate:

    P = cols V_dd (duty I_row + (1 - duty) I_idle),   duty = rows t_row frame_rate

(the readout is rows x t_row of each frame; the control lines' drivers are left out). The estimate
beside it: cols V_dd (duty I_bias + I_bias) (load and mirror at their bias)."""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError
from .run import run


def power(design, draw=None, backend: str = "batch") -> dict:
    from ..circuits.cds import cds_bench, timing_of
    from .signal import flush_exposure
    t0 = flush_exposure(design)
    cell = design.cell()
    srcs = ("vdd", "vrstd") if cell.port("vrst") else ("vdd",)
    t1 = t0 + 2 * timing_of(design).t_row   # an exposure with an idle stretch before its read
    net = cds_bench(design, cell, [t0, t1], [[0.0, 0.0]], title="role_power", saves=tuple(f"i({s})" for s in srcs))
    (r,) = run([net], design, draw, backend)
    tm, st = timing_of(design), net.meta["frames"]["starts"]
    a = design.array
    read0 = st[1] + tm.frame(t1).t_read
    t, i = r.time, -sum(r[f"i({s})"] for s in srcs)
    row = (t >= read0) & (t <= read0 + tm.t_row)
    idle = (t >= st[1] + tm.t_shutter) & (t <= read0)
    i_row = float(np.trapezoid(i[row], t[row]) / tm.t_row)
    i_idle = float(np.trapezoid(i[idle], t[idle]) / (t[idle][-1] - t[idle][0]))
    duty = a.rows * tm.t_row * a.frame_rate
    if duty > 1:
        raise ConfigError(design.source, "array.frame_rate", a.frame_rate,
                          f"at most {1 / (a.rows * tm.t_row):.4g} Hz (the rows' reads must fit in a frame: "
                          f"{a.rows} x {tm.t_row * 1e6:.4g} us)")
    vdd = design.tech.supply
    chip = a.cols * vdd * (duty * i_row + (1 - duty) * i_idle)
    est = a.cols * vdd * design.column.bias * (1 + duty)
    return {"chip_W": chip, "row_A": i_row, "idle_A": i_idle, "duty": duty, "estimate_W": est,
            "column_W": chip / a.cols}
