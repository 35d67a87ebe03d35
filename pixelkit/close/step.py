"""One step of ``pixelkit close``: casadi (IPOPT) on the linear models inside the trust region.

The models: for every modelled (spec, condition) pair i, its margin less its target,
m_i(u0 + d) ~ m_i + g_i . d (g_i from finite differences in SPICE, corrected by the secant of
every candidate simulated since); the objective f(u0 + d) ~ f + g_f . d (to minimise). d is
bounded by the knobs' bounds and the trust region |d_j| <= radius.

- ``restore``: maximise t subject to m_i + g_i . d >= t, t <= 0: the step that raises the
  smallest margin most (to 0 = every target met, in the model). At its optimum the multipliers
  lambda_i >= 0 of the margin rows sum to 1 and, with those of the bounds, balance the gradients
  (sum lambda_i g_i + bound terms = 0): when t* < 0 no step improves every row with lambda_i > 0
  at once, and those rows are the specs that conflict (a certificate in the linear model; close
  states it at a point where the trust region has shrunk without the SPICE re-verification
  improving, i.e. a local max-min point of the real margins).
- ``optimise``: minimise g_f . d subject to m_i + g_i . d >= 0: the objective, every target kept.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import math

import casadi as ca
import numpy as np

#: A row counts in a conflict when its pull (multiplier x gradient norm) is above this share of all.
CONFLICT_SHARE = 0.02
#: Weight of |d|^2 (per radius^2): picks the shortest of equally good steps.
REGULARISE = 1e-6


@dataclass
class Model:
    keys: list                      # (spec, condition) per row
    m: np.ndarray                   # margins less targets at u0
    g: np.ndarray                   # rows x knobs
    f: float | None = None          # objective to minimise (normalised), at u0
    gf: np.ndarray | None = None


@dataclass
class Step:
    d: np.ndarray
    t: float                        # predicted smallest margin less target after the step
    f: float | None                 # predicted objective
    ok: bool
    multipliers: dict = field(default_factory=dict)   # row key -> share of the pull (restore only)
    bounds: dict = field(default_factory=dict)        # knob index -> "min" / "max" when its bound binds


def _box(u0, lo, hi, radius):
    return np.maximum(lo - u0, -radius), np.minimum(hi - u0, radius)


def _opti():
    opti = ca.Opti()
    opti.solver("ipopt", {"print_time": False, "error_on_fail": False},
                {"print_level": 0, "sb": "yes", "tol": 1e-10, "max_iter": 500})
    return opti


def restore(model: Model, u0, lo, hi, radius: float, cap: float = 0.0) -> Step:
    """Maximise the smallest modelled margin (up to ``cap``) within the trust region."""
    n = len(u0)
    dlo, dhi = _box(u0, lo, hi, radius)
    opti = _opti()
    d, t = opti.variable(n), opti.variable()
    rows = model.m + ca.mtimes(ca.DM(model.g), d)
    c_rows = rows >= t
    opti.subject_to(c_rows)
    c_lo, c_hi = d >= ca.DM(dlo), d <= ca.DM(dhi)
    opti.subject_to(c_lo)
    opti.subject_to(c_hi)
    opti.subject_to(t <= cap)
    opti.minimize(-t + REGULARISE * ca.sumsqr(d) / max(radius, 1e-9) ** 2)
    opti.set_initial(d, 0.0)
    opti.set_initial(t, float(np.min(model.m)) if len(model.m) else 0.0)
    sol = opti.solve()
    ok = opti.stats().get("success", False)
    dv = np.clip(np.array(sol.value(d), float).reshape(n), dlo, dhi)
    pred = model.m + model.g @ dv
    lam = np.array(sol.value(opti.dual(c_rows)), float).reshape(-1) if ok else np.zeros(len(model.m))
    # a row's pull on the step is lambda_i |g_i| (lambda alone scales with 1 / |g_i|): the rows that are
    # active at the optimum and pull are the conflict
    pull = np.abs(lam) * np.linalg.norm(model.g, axis=1)
    active = np.abs(pred - float(sol.value(t))) <= 1e-6 * max(1.0, float(np.abs(pred).max(initial=0)))
    share = pull / max(pull.sum(), 1e-300)
    mult = {k: float(w) for k, w, a in zip(model.keys, share, active) if a and w > CONFLICT_SHARE}
    bounds = {}
    for j in range(n):
        if dv[j] <= (lo - u0)[j] + 1e-9 and (lo - u0)[j] >= -radius:
            bounds[j] = "min"
        elif dv[j] >= (hi - u0)[j] - 1e-9 and (hi - u0)[j] <= radius:
            bounds[j] = "max"
    f = None if model.gf is None else float(model.f + model.gf @ dv)
    return Step(dv, float(pred.min()) if len(pred) else 0.0, f, ok, mult, bounds)


def optimise(model: Model, u0, lo, hi, radius: float, cushion: float = 0.0) -> Step:
    """Minimise the modelled objective keeping every modelled margin >= its target (+ ``cushion``)."""
    n = len(u0)
    dlo, dhi = _box(u0, lo, hi, radius)
    opti = _opti()
    d = opti.variable(n)
    if len(model.m):   # no row: no spec close enough to its limit to be modelled (the grid checks them all)
        opti.subject_to(model.m + ca.mtimes(ca.DM(model.g), d) >= min(cushion, max(float(np.min(model.m)), 0.0)))
    opti.subject_to(d >= ca.DM(dlo))
    opti.subject_to(d <= ca.DM(dhi))
    opti.minimize(ca.mtimes(ca.DM(model.gf).T, d) + REGULARISE * ca.sumsqr(d) / max(radius, 1e-9) ** 2)
    opti.set_initial(d, 0.0)
    sol = opti.solve()
    ok = opti.stats().get("success", False)
    dv = np.clip(np.array(sol.value(d), float).reshape(n), dlo, dhi)
    pred = model.m + model.g @ dv
    return Step(dv, float(pred.min()) if len(pred) else math.inf, float(model.f + model.gf @ dv), ok)


def correct(model: Model, m_at: np.ndarray, d: np.ndarray, u0, lo, hi, radius: float, cushion: float) -> np.ndarray:
    """A second-order correction of step ``d`` (Fletcher's): the candidate at u0 + d gave the margins
    less targets ``m_at`` (some below 0: the constraints curve away from their tangents); the shortest
    move e with m_at + g e >= cushion, inside the bounds and the trust region, puts it back on the
    passing side of the linear models taken there. Returns d + e."""
    n = len(u0)
    dlo, dhi = _box(u0, lo, hi, radius)
    opti = _opti()
    e = opti.variable(n)
    opti.subject_to(ca.DM(m_at) + ca.mtimes(ca.DM(model.g), e) >= cushion)
    opti.subject_to(ca.DM(d) + e >= ca.DM(dlo))
    opti.subject_to(ca.DM(d) + e <= ca.DM(dhi))
    opti.minimize(ca.sumsqr(e))
    opti.set_initial(e, 0.0)
    sol = opti.solve()
    return np.clip(d + np.array(sol.value(e), float).reshape(n), dlo, dhi)
