"""Fitting candidate effects and ranking them.

Every model, the nominal one included, carries the test set-up's unknown gain
and offset (v_meas = a + b v_model; one pair for the whole dataset). Each
candidate is fitted by bounded least squares on the training rows; candidates
are ranked by BIC on the training rows (n ln(RSS/n) + k ln n) and checked on the
held-out rows. The best candidate is reported only if it beats the nominal model
clearly: BIC lower by more than ``BIC_MARGIN`` and held-out RMS lower by at least
``HELDOUT_GAIN``; otherwise the answer is ``none``. Parameter intervals come from
the Jacobian at the optimum (95 %); a parameter whose interval spans more than its
own value, or which sits on a bound, is flagged.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import least_squares

from .effects import EFFECTS, column_shift
from .nominal import predict

BIC_MARGIN = 10.0
HELDOUT_GAIN = 0.10


def _column_keys(X):
    return X["arr"] * 100000 + X["col"].astype(int)


def model_fn(name, nom, X, cols=None):
    """(function of full parameter vector -> prediction, parameter specs) for candidate ``name``."""
    if name == "none":
        specs = []

        def f(theta):
            return theta[0] + theta[1] * predict(nom, X)
    elif name == "column_fpn":
        keys = _column_keys(X)
        idx = np.searchsorted(cols, keys)
        specs = [("offset", -0.5, 0.5, 1e-3)] * len(cols) + [("gain", -0.5, 0.5, 1e-3)] * len(cols)
        base = predict(nom, X)

        def f(theta):
            o, g = theta[2:2 + len(cols)], theta[2 + len(cols):]
            return theta[0] + theta[1] * (base + column_shift(X, nom.gain_afe, o[idx], g[idx]))
    else:
        params, fn = EFFECTS[name]
        specs = [(p.name, p.lo, p.hi, p.scale) for p in params]

        def f(theta):
            return theta[0] + theta[1] * predict(nom, X, fn(X, theta[2:]))
    return f, specs


def fit(name, nom, X_train, y_train, cols=None):
    f, specs = model_fn(name, nom, X_train, cols)
    scales = np.array([1e-3, 1e-2] + [s[3] for s in specs])
    lo = np.array([-1.0, 0.5] + [s[1] for s in specs]) / scales
    hi = np.array([1.0, 2.0] + [s[2] for s in specs]) / scales
    if name in EFFECTS and EFFECTS[name][1] is not None:
        x0 = np.array([0.0, 1.0] + [p.x0 for p in EFFECTS[name][0]]) / scales
    else:
        x0 = np.array([0.0, 1.0] + [0.0] * len(specs)) / scales
    x0 = np.clip(x0, lo + 1e-12 * (hi - lo), hi - 1e-12 * (hi - lo))

    def resid(u):
        return f(u * scales) - y_train

    best = None
    starts = [x0]
    if specs and name not in ("column_fpn",):
        mid = x0.copy()
        mid[2:] = np.clip(np.array([s[3] for s in specs]) / scales[2:], lo[2:], hi[2:])
        starts.append(mid)
    for s in starts:
        r = least_squares(resid, s, bounds=(lo, hi), x_scale=1.0, method="trf", max_nfev=200)
        if best is None or r.cost < best.cost:
            best = r
    theta = best.x * scales
    n, k = len(y_train), len(theta)
    rss = float(np.sum(best.fun ** 2))
    info = _intervals(best, scales, n, k, lo * scales, hi * scales, theta)
    return {"theta": theta, "rss": rss, "k": k, "n": n,
            "bic": n * math.log(max(rss, 1e-30) / n) + k * math.log(n),
            "specs": specs, "intervals": info}


def _intervals(res, scales, n, k, lo, hi, theta):
    out = []
    dof = max(n - k, 1)
    s2 = float(np.sum(res.fun ** 2)) / dof
    J = res.jac * (1.0 / scales)[None, :]
    try:
        jtj = J.T @ J
        cond = np.linalg.cond(jtj)
        cov = np.linalg.pinv(jtj) * s2
        sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    except np.linalg.LinAlgError:
        cond, sd = np.inf, np.full(k, np.inf)
    for i in range(2, k):
        at_bound = bool(np.isclose(theta[i], lo[i], rtol=0, atol=1e-9 * scales[i])
                        or np.isclose(theta[i], hi[i], rtol=0, atol=1e-9 * scales[i]))
        half = 1.96 * sd[i]
        out.append({"value": float(theta[i]), "ci95": [float(theta[i] - half), float(theta[i] + half)],
                    "identifiable": bool(np.isfinite(cond) and cond < 1e14 and half < abs(theta[i]) and not at_bound),
                    "at_bound": at_bound})
    return out


def evaluate(name, nom, X, fitres, cols=None):
    f, _ = model_fn(name, nom, X, cols)
    return f(fitres["theta"])
