"""Depletion capacitance of a junction with area and perimeter ([Thesis2019] eq. 3.5).

    C_jdep(V_R) = C_j0B A / (1 + V_R/phi_B)^m_j + C_j0SW P / (1 + V_R/phi_SW)^m_jsw

``V_R`` is the reverse bias (V_R > 0 reverse). The charge stored between zero bias
and ``V_R`` has the closed form

    Q(V_R) = C_j0 A phi/(1-m) [(1 + V_R/phi)^(1-m) - 1] + (same for the sidewall)

(the integral of C over V), which the discharge model inverts. SPICE's diode
uses the same depletion formula for reverse bias (and a linear extension past
FC*phi in forward bias, which the pixel never reaches in its swing).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Junction:
    """Grading parameters of one junction type (SI units)."""
    cj: float      # F/m^2
    mj: float
    pb: float      # V
    cjsw: float    # F/m
    mjsw: float
    pbsw: float    # V

    @classmethod
    def of(cls, params) -> "Junction":
        """From any object with cj/mj/pb/cjsw/mjsw/pbsw (a technology section)."""
        return cls(params.cj, params.mj, params.pb, params.cjsw, params.mjsw, params.pbsw)


def _check_bias(v_r, j: Junction):
    v = np.asarray(v_r, dtype=float)
    if np.any(v <= -min(j.pb, j.pbsw)):
        raise ValueError("the depletion formula needs V_R > -phi (reverse or weak forward bias)")
    return v


def capacitance(v_r, area: float, perimeter: float, j: Junction):
    """C_jdep at reverse bias ``v_r`` (V) for ``area`` (m^2) and ``perimeter`` (m), in F."""
    v = _check_bias(v_r, j)
    return (j.cj * area / (1.0 + v / j.pb) ** j.mj
            + j.cjsw * perimeter / (1.0 + v / j.pbsw) ** j.mjsw)


def charge(v_r, area: float, perimeter: float, j: Junction):
    """Depletion charge Q(V_R) = integral_0^V_R C dV, in C (zero at zero bias)."""
    v = _check_bias(v_r, j)
    qb = j.cj * area * j.pb / (1 - j.mj) * ((1.0 + v / j.pb) ** (1 - j.mj) - 1.0)
    qs = j.cjsw * perimeter * j.pbsw / (1 - j.mjsw) * ((1.0 + v / j.pbsw) ** (1 - j.mjsw) - 1.0)
    return qb + qs


@dataclass(frozen=True)
class Node:
    """A circuit node's capacitance: junction terms (area, perimeter, Junction) plus a fixed C."""
    terms: tuple
    c_fixed: float = 0.0

    def capacitance(self, v_r):
        return sum(capacitance(v_r, a, p, j) for a, p, j in self.terms) + self.c_fixed

    def charge(self, v_r):
        return sum(charge(v_r, a, p, j) for a, p, j in self.terms) + self.c_fixed * np.asarray(v_r)

    def bias_for_charge(self, q):
        """Invert ``charge(v) = q`` for v (Newton; the function is monotone)."""
        q = np.asarray(q, dtype=float)
        v = q / self.capacitance(0.0)
        lo = -0.9 * min(min(j.pb, j.pbsw) for _, _, j in self.terms)
        for _ in range(80):
            v = np.maximum(v, lo)
            step = (self.charge(v) - q) / self.capacitance(v)
            v = v - step
            if np.all(np.abs(step) < 1e-12):
                break
        return v
