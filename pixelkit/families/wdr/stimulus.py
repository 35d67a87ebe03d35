"""The time-to-voltage coding waveforms as PWL stimuli (paper fig. 3).

With T = ``coding.t_unit``, N = ``coding.steps`` and the levels v_low, v_high
(1 V and 2 V in the paper), both start when the exposure starts (t = 0 here):

- signal1: V-shaped waves. It rises from v_low to v_high over [0, T], and over
  every octave [2^k T, 2^(k+1) T] (k = 0 .. N-1) it runs once between the two
  levels, the slope flipping at T, 2T, 4T, ..., 2^N T: at 2^k T it sits at
  v_high when k is even and at v_low when k is odd. Within an octave it
  therefore codes the *relative* position of t_c, the same fraction of every
  octave: a logarithmic fine code.
- signal2: a ramp falling (v_high - v_low) / 2^N per T, from v_high at 0 to v_low
  at 2^N T: a linear coarse code that says which octave t_c is in.
"""
from __future__ import annotations

from ...spice.netlist import Pwl


def signal1_points(t_unit: float, steps: int, v_low: float, v_high: float, t0: float = 0.0) -> tuple:
    pts = [(t0, v_low), (t0 + t_unit, v_high)]
    for k in range(1, steps + 1):
        pts.append((t0 + (2 ** k) * t_unit, v_high if k % 2 == 0 else v_low))
    return tuple(pts)


def signal2_points(t_unit: float, steps: int, v_low: float, v_high: float, t0: float = 0.0) -> tuple:
    return ((t0, v_high), (t0 + (2 ** steps) * t_unit, v_low))


def _hold(points, t_after: float) -> tuple:
    """Flat before the first point (from 0) and after the last (until ``t_after``)."""
    pts = list(points)
    if pts[0][0] > 0:
        pts.insert(0, (0.0, pts[0][1]))
    if t_after > pts[-1][0]:
        pts.append((t_after, pts[-1][1]))
    return tuple(pts)


def signal1(coding, t0: float, t_stop: float) -> Pwl:
    return Pwl(_hold(signal1_points(coding.t_unit, coding.steps, coding.v_low, coding.v_high, t0), t_stop))


def signal2(coding, t0: float, t_stop: float) -> Pwl:
    return Pwl(_hold(signal2_points(coding.t_unit, coding.steps, coding.v_low, coding.v_high, t0), t_stop))
