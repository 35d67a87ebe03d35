"""Photodiode discharge under constant current, with the voltage-dependent C(V).

Charge balance on the node: dQ(V)/dt = -I, so Q(V(t)) = Q(V0) - I t, and V(t) is
the inverse of the closed-form depletion charge (see ``junction``). The linear
approximation of the thesis [Thesis2019] (eq. 3.9, fig. 3.6) takes C fixed at the reset
bias: V(t) = V0 - I t / C(V0), t_sat = V C / I.
"""
from __future__ import annotations

import numpy as np

from .junction import Node


def voltage(t, node: Node, v0: float, current: float):
    """Reverse bias V(t) of ``node`` discharged from ``v0`` by ``current`` (A)."""
    q = node.charge(v0) - current * np.asarray(t, dtype=float)
    return node.bias_for_charge(q)


def voltage_linear(t, c: float, v0: float, current: float):
    return v0 - current * np.asarray(t, dtype=float) / c


def time_to(node: Node, v0: float, v1: float, current: float) -> float:
    """Time to discharge ``node`` from ``v0`` to ``v1`` at constant ``current`` (C(V) exact)."""
    return float(node.charge(v0) - node.charge(v1)) / current


def time_to_linear(c: float, dv: float, current: float) -> float:
    """t = dV C / I with C fixed (the thesis's t_sat = 2.5 V C_jdep / I_ph)."""
    return dv * c / current
