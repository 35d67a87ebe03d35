"""Fitting candidate effects: weighted least squares with the test set-up's gain and offset.

Every model, the nominal one included, carries the test set-up's unknown gain
and offset (v_meas = a + b v_model; one pair for the whole dataset), bounded to
a stated plausible range (``SetupBounds``; default gain 1 +- 5 %, offset +- 25
mV): a fit that needs more sits on the bound, and the result says so instead of
silently accepting a set-up gain of 0.9. Rows are weighted by their noise
``sigma`` (measurement noise of the averaged value plus the surrogate's own
error). Parameter intervals come from the Jacobian at the optimum (95 %); a
parameter whose interval spans more than its own value, or which sits on a
bound, is flagged as not identifiable. Per-column terms (``column_pixel``,
``column_afe``) are mismatch drawn around zero: they carry a Gaussian prior
(``COLUMN_PRIOR``), so a column seen in one or two training rows is not given
a wild value that no held-out row supports. Each fit starts from the parameters'
``x0`` and one typical size away, and from a parameter's ``starts`` where its
response is not monotone (readout light: the op-amp clamp's steps); the lowest
cost wins.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from .effects import EFFECTS, column_shift
from .nominal import predict


@dataclass(frozen=True)
class SetupBounds:
    """Plausible test set-up: gain within 1 +- ``gain_tol``, offset within +- ``offset_V``."""
    gain_tol: float = 0.05
    offset_V: float = 0.025


def column_keys(X):
    return X["arr"] * 100000 + X["col"].astype(int)


# Per-column terms are mismatch, drawn around zero: a Gaussian prior of this width keeps a
# column seen in one or two rows from taking a wild value (a random-effects fit, not free constants).
COLUMN_PRIOR = {"offset_pix": 0.01, "gain_pix": 0.02, "offset_afe": 0.01, "gain_afe": 0.02}


def _column_specs(name, cols):
    n = len(cols)
    if name == "column_pixel":
        kinds = ("offset_pix", "gain_pix")
    else:
        kinds = ("offset_afe", "gain_afe", "offset_pix")
    return [(k, -0.3, 0.3, 1e-3) for k in kinds for _ in range(n)]


def model_fn(name, nom, X, cols=None):
    """(function of full parameter vector -> prediction, parameter specs) for candidate ``name``."""
    if name == "none":
        specs = []
        base = predict(nom, X)

        def f(theta):
            return theta[0] + theta[1] * base
    elif name in ("column_pixel", "column_afe"):
        idx = np.searchsorted(cols, column_keys(X))
        specs = _column_specs(name, cols)
        base = predict(nom, X)
        n = len(cols)
        zero = np.zeros(X["afe"].size)

        def f(theta):
            p = theta[2:]
            if name == "column_pixel":
                sh = column_shift(X, nom.gain_afe, p[:n][idx], zero, zero, p[n:][idx])
            else:
                sh = column_shift(X, nom.gain_afe, p[2 * n:][idx], p[:n][idx], -p[n:2 * n][idx])
            return theta[0] + theta[1] * (base + sh)
    else:
        params, fn = EFFECTS[name]
        specs = [(p.name, p.lo, p.hi, p.scale) for p in params]

        def f(theta):
            return theta[0] + theta[1] * predict(nom, X, fn(X, theta[2:]))
    return f, specs


def fit(name, nom, X_train, y_train, sigma, cols=None, setup: SetupBounds = SetupBounds()):
    f, specs = model_fn(name, nom, X_train, cols)
    scales = np.array([1e-3, 1e-2] + [s[3] for s in specs])
    lo = np.array([-setup.offset_V, 1 - setup.gain_tol] + [s[1] for s in specs]) / scales
    hi = np.array([setup.offset_V, 1 + setup.gain_tol] + [s[2] for s in specs]) / scales
    if name in EFFECTS and EFFECTS[name][1] is not None:
        x0 = np.array([0.0, 1.0] + [p.x0 for p in EFFECTS[name][0]]) / scales
    else:
        x0 = np.array([0.0, 1.0] + [0.0] * len(specs)) / scales
    x0 = np.clip(x0, lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))

    prior = np.array([COLUMN_PRIOR.get(sp[0], np.inf) for sp in specs])
    has_prior = bool(np.isfinite(prior).any())
    prior_w = np.where(np.isfinite(prior), scales[2:] / prior, 0.0)

    def resid(u):
        r = (f(u * scales) - y_train) / sigma
        return np.concatenate([r, u[2:] * prior_w]) if has_prior else r

    starts = [x0]
    if specs and name in EFFECTS and EFFECTS[name][1] is not None:
        s = x0.copy()   # a second start one typical size away (downwards when the parameter may be negative)
        sign = np.where(np.array([sp[1] for sp in specs]) < 0, -1.0, 1.0)
        s[2:] = np.clip(sign * np.array([sp[3] for sp in specs]) / scales[2:], lo[2:] + 1e-9, hi[2:] - 1e-9)
        starts.append(s)
        for j, prm in enumerate(EFFECTS[name][0]):
            for v in prm.starts:
                s = x0.copy()
                s[2 + j] = np.clip(v / scales[2 + j], lo[2 + j] + 1e-9, hi[2 + j] - 1e-9)
                starts.append(s)
    best = None
    for s in starts:
        r = least_squares(resid, s, bounds=(lo, hi), x_scale=1.0, method="trf", max_nfev=150)
        if best is None or r.cost < best.cost:
            best = r
    theta = best.x * scales
    n, k = len(y_train), len(theta)
    chi2 = float(np.sum(best.fun ** 2))
    info = _intervals(best, scales, n, k, lo * scales, hi * scales, theta)
    setup_at_bound = bool(np.isclose(abs(theta[1] - 1), setup.gain_tol, rtol=1e-3)
                          or np.isclose(abs(theta[0]), setup.offset_V, rtol=1e-3))
    return {"theta": theta, "chi2": chi2, "k": k, "n": n,
            "bic": chi2 + k * math.log(n),
            "specs": specs, "intervals": info, "setup_at_bound": setup_at_bound}


def _intervals(res, scales, n, k, lo, hi, theta):
    out = []
    J = res.jac * (1.0 / scales)[None, :]
    try:
        jtj = J.T @ J
        cond = np.linalg.cond(jtj)
        cov = np.linalg.pinv(jtj) * max(1.0, float(np.sum(res.fun ** 2)) / max(n - k, 1))
        sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    except np.linalg.LinAlgError:
        cond, sd = np.inf, np.full(k, np.inf)
    for i in range(2, k):
        at_bound = bool(np.isclose(theta[i], lo[i], rtol=0, atol=1e-6 * scales[i])
                        or np.isclose(theta[i], hi[i], rtol=0, atol=1e-6 * scales[i]))
        half = 1.96 * sd[i]
        out.append({"value": float(theta[i]), "ci95": [float(theta[i] - half), float(theta[i] + half)],
                    "identifiable": bool(np.isfinite(cond) and cond < 1e14 and half < abs(theta[i]) and not at_bound),
                    "at_bound": at_bound})
    return out


def evaluate(name, nom, X, fitres, cols=None):
    f, _ = model_fn(name, nom, X, cols)
    return f(fitres["theta"])
