"""Pixel figures: double-sampled column signal, output swing, discharge slope, settling."""
from __future__ import annotations

import numpy as np


def double_sampled(result, node: str, timing, row: int = 0) -> float:
    """Reset level minus signal level of ``row`` on ``node`` (V): the pixel's signal."""
    return float(result.at(node, timing.t_reset_level(row)) - result.at(node, timing.t_signal(row)))


def levels(result, node: str, timing, row: int = 0) -> tuple[float, float]:
    """(signal level, reset level) of ``row`` on ``node``."""
    return float(result.at(node, timing.t_signal(row))), float(result.at(node, timing.t_reset_level(row)))


def discharge_slope(result, node: str, t0: float, t1: float) -> float:
    """Least-squares slope dV/dt of ``node`` over [t0, t1] (V/s)."""
    m = (result.time >= t0) & (result.time <= t1)
    if m.sum() < 2:
        raise ValueError(f"fewer than two points of {node} in [{t0:g}, {t1:g}] s")
    return float(np.polyfit(result.time[m], result[node][m], 1)[0])


def settling_time(t, v, t_start: float, t_end: float, tol: float) -> float:
    """Time after ``t_start`` from which ``v`` stays within ``tol`` of its value at ``t_end``."""
    m = (t >= t_start) & (t <= t_end)
    tt, vv = t[m], v[m]
    final = np.interp(t_end, t, v)
    outside = np.nonzero(np.abs(vv - final) > tol)[0]
    if outside.size == 0:
        return 0.0
    k = outside[-1]
    return float(tt[min(k + 1, tt.size - 1)] - t_start)


def target_current(currents, signals, target: float) -> float:
    """Photocurrent at which the (monotone) signal-vs-current curve reaches ``target``."""
    i, s = np.asarray(currents, float), np.asarray(signals, float)
    order = np.argsort(i)
    i, s = i[order], s[order]
    s_mono = np.maximum.accumulate(s)
    if not s_mono[0] <= target <= s_mono[-1]:
        raise ValueError(f"target {target:.4g} V outside the swept signal range "
                         f"[{s_mono[0]:.4g}, {s_mono[-1]:.4g}] V")
    k = int(np.searchsorted(s_mono, target))
    k = min(max(k, 1), i.size - 1)
    return float(i[k - 1] + (target - s[k - 1]) * (i[k] - i[k - 1]) / (s[k] - s[k - 1]))
