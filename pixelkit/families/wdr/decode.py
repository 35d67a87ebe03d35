"""Decoder: from the stored voltages (signal 1 on C1, signal 2 on C2, signal 3 =
V(int)) back to the comparator time t_c and the photocurrent.

Coarse: signal2 falls linearly, so t2 = (v_high - V2) / (v_high - v_low) * 2^N T.
Fine: in octave k ([2^k T, 2^(k+1) T]) signal1 runs from v_high to v_low when k
is even and from v_low to v_high when k is odd (stimulus.py), so a sample V1 in
octave k means t = 2^k T (1 + f) with f = (v_high - V1)/(v_high - v_low) for even
k, (V1 - v_low)/(v_high - v_low) for odd k (and t = f' T in [0, T] with
f' = (V1 - v_low)/(v_high - v_low)). Every octave gives one candidate; the one
nearest the coarse time wins. The coded range is [T, 2^N T] (a flip before T is
beyond I_max). Because signal1 is continuous, the candidates of two neighbouring
octaves mirror each other about their common boundary (the later octave twice
as wide): a coarse code that is off by dt can pick the wrong one only within dt
of a boundary, and then costs at most three times the distance to it (the read-in switches' gate feedthrough
shifts the coarse code by ~0.8 T: measured at the bright end).
The sample is taken t_d (the delay of the sampling pulse) after the flip:
t_c = t_sample - t_d.

A pixel whose coarse time is at or beyond the end of the frame never flipped
(low light): its intensity comes from signal 3 over the fixed exposure, with the
dark current as a function of the node voltage (``dark_model``) integrated along
the discharge.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from .model import delta_q, node_capacitance


def sample_time(v1: float, v2: float, coding) -> float:
    """Time (since the exposure started) at which C1/C2 were sampled."""
    span = coding.v_high - coding.v_low
    n = 2 ** coding.steps
    t_coarse = (coding.v_high - v2) / span * n * coding.t_unit
    cands = []
    for k in range(coding.steps):
        f = (coding.v_high - v1) / span if k % 2 == 0 else (v1 - coding.v_low) / span
        cands.append((2 ** k) * coding.t_unit * (1.0 + f))
    return min(cands, key=lambda t: abs(t - t_coarse))


def dark_model(design, v_start: float, v_half: float, v_end: float) -> tuple[float, float]:
    """Dark current I_d(V) = a + g V from a dark pixel read at half and full exposure.

    A dark current that changes with the reverse bias (a tunnelling term does: GF180's
    foundry card gave 1.27 pA at 2.0 V and 0.32 pA at 1.25 V) would make one dark rate
    over-subtract for pixels that have moved away from the dark pixel's voltage; the two
    half-frame rates, each at its mean voltage, give the slope g. When the dark pixel moves
    less than ``DARK_MIN_MOVE`` over the frame (the thermal dark current: ~20 uV), the
    half-frame rates differ by SPICE's numerical error only and one rate is used.
    """
    half = (2 ** design.coding.steps) * design.coding.t_unit / 2
    i1 = float(delta_q(design, v_start, v_half)) / half
    i2 = float(delta_q(design, v_half, v_end)) / half
    m1, m2 = (v_start + v_half) / 2, (v_half + v_end) / 2
    if abs(v_start - v_end) < DARK_MIN_MOVE:
        return (i1 + i2) / 2, 0.0
    g = (i1 - i2) / (m1 - m2) if abs(m1 - m2) > 1e-6 else 0.0
    return i1 - g * m1, g


DARK_MIN_MOVE = 5e-3


def low_light_current(design, v_start: float, v3: float, dark: tuple[float, float]) -> float:
    """I such that C(V) dV/dt = -(I + a + g V) takes the node from v_start to v3 in 2^N T."""
    t_exp = (2 ** design.coding.steps) * design.coding.t_unit
    a, g = dark
    v = np.linspace(v3, v_start, 201)
    c = np.array([node_capacitance(design, x) for x in v])

    def excess(i):
        return float(np.trapezoid(c / (i + a + g * v), v)) - t_exp

    lo = -float(np.min(a + g * v)) * (1 - 1e-9) + 1e-21   # the rate must stay positive
    hi = abs(lo) + 10 * float(delta_q(design, v_start, v3)) / t_exp + 1e-15
    return float(brentq(excess, lo, hi, xtol=1e-22, rtol=1e-10))


def knee_current(design, v_start: float, dark: tuple[float, float]) -> float:
    """The photocurrent that reaches V0 exactly at the end of the frame (dark current included)."""
    return low_light_current(design, v_start, design.pixel.v0, dark)


def decode(design, v1: float, v2: float, v3: float, v_start: float, dark=(0.0, 0.0)) -> dict:
    """t_c (s; None at low light), the regime and the photocurrent (A); ``dark`` = (a, g)."""
    cd, px = design.coding, design.pixel
    t_exp = (2 ** cd.steps) * cd.t_unit
    t_coarse = (cd.v_high - v2) / (cd.v_high - cd.v_low) * t_exp
    if t_coarse >= t_exp - 0.5 * cd.t_unit:
        return {"regime": "low", "t_c_s": None, "i_A": low_light_current(design, v_start, v3, dark)}
    t_c = sample_time(v1, v2, cd) - cd.t_delay
    i_dark = dark[0] + dark[1] * (v_start + px.v0) / 2
    i = float(delta_q(design, v_start, px.v0)) / t_c - i_dark
    return {"regime": "high", "t_c_s": t_c, "i_A": i}
