"""Closed-form transfer of the ratio pixel, derived from the circuit, and its decoder.

Loop (circuit.py). In weak inversion a MOSFET with gate G, source S and bulk at
ground carries I = I0 exp((kappa V_G - V_S)/U_T) (bulk-referenced). M1 shares its
gate with M4 and M2 with M3; M3/M4 share the source v_source, M1/M2 the source s:

    I_1 / I_4 = exp((v_source - V_s)/U_T) = I_2 / I_3
    =>  I_out+ / I_out- = I_1 / I_2 = I_4 / I_3 = I_PD- / I_PD+ = 1 / R_F

independent of kappa, I0 and the light level (as long as all four devices stay
in weak inversion and I0 is common). With the tail, I_out+ + I_out- = I_bias:

    I_out+ = I_bias / (1 + R_F),   I_out- = I_bias R_F / (1 + R_F).

Readout. Both columns start at V_dd and are discharged by constant currents
(the row-select NMOS cascodes the outputs, the clamp keeps a tripped column's
current flowing); an inverter trips at V_th, so t_+/- = C (V_dd - V_th)/I_out+/-
and the counter measures

    T_c-r = t_+ - t_- = C (V_dd - V_th) (1/I_out+ - 1/I_out-)
          = C (V_dd - V_th) / I_bias * [(1 + R_F) - (1 + R_F)/R_F]
          = tau (R_F - 1/R_F),          tau = C (V_dd - V_th) / I_bias,

which confirms the brief's T/tau = R_F - 1/R_F. Inverting (R_F > 0):
R_F^2 - x R_F - 1 = 0 with x = T/tau gives R_F = (x + sqrt(x^2 + 4))/2
(R_F = 1 at x = 0, (1 + sqrt 5)/2 = 1.618 at x = 1, ~x for x >> 1). When
R_F < 1 the other column trips first; the sign of T says which.

A uniform field (R_F = 1) trips both columns at t = 2 tau: that is how the
experiment calibrates tau, independently of the ratios it then checks.
"""
from __future__ import annotations

import math


def interval_over_tau(rf: float) -> float:
    """T_c-r / tau for photocurrent ratio R_F = I_PD+ / I_PD-."""
    return rf - 1.0 / rf


def ratio_from_interval(x: float) -> float:
    """R_F from x = T_c-r / tau (signed: x < 0 means R_F < 1)."""
    rf = (abs(x) + math.sqrt(x * x + 4.0)) / 2.0
    return rf if x >= 0 else 1.0 / rf


def counter(t_interval: float, t_lsb: float, bits: int) -> int:
    """Behavioural column counter: clock periods from the first trip to the second.

    Starts at the first inverter trip, counts whole periods of T_LSB, stops at the
    second trip and saturates at 2^bits - 1. Signed like the interval.
    """
    n = min(int(abs(t_interval) // t_lsb), 2 ** bits - 1)
    return n if t_interval >= 0 else -n


def ratio_from_count(count: int, t_lsb: float, tau: float) -> float:
    """The decoder: counts back to R_F (lower edge of the count's interval)."""
    return ratio_from_interval(count * t_lsb / tau)


def resolution(lsb_per_tau: float, bits: int) -> dict:
    """Smallest resolvable ratio (one count), largest (full scale), neighbour DR.

    The paper (T_LSB = tau, 5 bits): R_F,min = 1.62, R_F,i = 31 / 1.62 = 19.14,
    25.6 dB; here R_F,max is the decoded full count (31.03 for 5 bits).
    """
    rf_min = ratio_from_interval(lsb_per_tau)
    rf_max = ratio_from_interval((2 ** bits - 1) * lsb_per_tau)
    return {"rf_min": rf_min, "rf_max": rf_max, "dr_adj_db": 20.0 * math.log10(rf_max / rf_min)}
