"""AFE figures and the finite-gain model of the SC double-sampling stage.

Derivation (charge conservation at the summing node vm of ``circuits.afe``):
phase 1 leaves C11 holding C11 (Vref - Vsig), C13 empty, C12 holding the offset
Vx1 - Vref; node x floats in phase 2, so C12's voltage is kept. In phase 2,

    C11 (Vref - Vsig) + Cp Vref = C11 (Vm - Vrst) + C13 (Vm - Vout) + Cp Vm
    Vout = A (Vref + Vos - Vx),   Vx = Vm + (Vx1 - Vref),   Vx1 = A (Vref + Vos) / (1 + A)

which solves to Vout = [Vref (1 + eps A/(1+A)) + eps A/(1+A) Vos] / (1 + eps)
- (C11/C13) (Vrst - Vsig) / (1 + eps), with eps = (C11 + C13 + Cp) / (A C13).
The gain error is -eps/(1+eps); the residual offset is ~eps Vos.
"""
from __future__ import annotations


def eps(c11: float, c13: float, gain: float, cp: float = 0.0) -> float:
    return (c11 + c13 + cp) / (gain * c13)


def ideal_output(vref: float, c11: float, c13: float, dv):
    """Eq. 3.1: Vout = Vref - (C11/C13)(Vrst - Vsig)."""
    return vref - (c11 / c13) * dv


def finite_gain_output(vref: float, c11: float, c13: float, gain: float, dv, cp: float = 0.0,
                       vos: float = 0.0):
    """Eq. 3.1 with the op-amp's finite DC gain (derivation in the module docstring)."""
    e = eps(c11, c13, gain, cp)
    k = e * gain / (1 + gain)
    return (vref * (1 + k) + k * vos) / (1 + e) - (c11 / c13) * dv / (1 + e)


def afe_output(result, timing, row: int, node: str = "out") -> float:
    """The AFE output at the end of phase 2 of cycle ``row``."""
    return float(result.at(node, timing.t_reset_level(row)))
