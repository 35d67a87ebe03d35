"""Fitting candidate effects: weighted least squares with the test set-up's gain and offset per probe.

Every model, the nominal one included, carries the test set-up's unknown gain
and offset for each probe (v_meas = a + b v_model; the pixel probe and the AFE
probe are read through different paths), bounded to a stated plausible range
(``SetupBounds``; default gain 1 +- 5 %, offset +- 25 mV): a fit that needs
more sits on the bound, and the result says so instead of silently accepting
a set-up gain of 0.9. The set-up's parameters are reported apart and are not
counted as the effect's. A bench whose calibration is stated (``gain_sd``,
``offset_sd_V``: its gain and offset known to that standard deviation) adds
one independent measurement of each set-up parameter of a probe in the data:
a Gaussian term of the fit (which also settles the split between an effect
and the set-up where the rows alone cannot), reported as ``calibration_chi2``
and counted in the BIC and, by ``diagnose``, beside the held-out rows. Rows are weighted by their noise ``sigma``
(measurement noise of the averaged value plus the surrogate's own error).
Parameter intervals come from the Jacobian at the optimum (95 %); a parameter
whose interval spans more than its own value, or which sits on a bound, is
flagged as not identifiable. Per-column terms (``effects.COLUMN_EFFECTS``)
carry a zero-mean Gaussian prior, so a column seen in one or two training rows
is not given a wild value that no held-out row supports; ``uniform=True`` fits
the same parameters with one value per array (the nested model of the
column-to-column spread test). Each fit starts from the parameters' ``x0`` and one
typical size away, and, where a parameter's response is not monotone (readout light:
the op-amp clamp's steps), from the best few values of a scan over its ``starts`` grid
(profile chi-square, the set-up solved exactly at each value); the lowest cost wins.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from .effects import COLUMN_EFFECTS, effect
from .nominal import predict, predict_sd


@dataclass(frozen=True)
class SetupBounds:
    """Plausible test set-up: gain within 1 +- ``gain_tol``, offset within +- ``offset_V``; and, when the
    bench's calibration is stated, its gain known to 1 +- ``gain_sd`` and its offset to 0 +- ``offset_sd_V``
    (one standard deviation, per probe)."""
    gain_tol: float = 0.05
    offset_V: float = 0.025
    gain_sd: float | None = None
    offset_sd_V: float | None = None


def calibration_terms(setup: SetupBounds, afe) -> list:
    """(index into SETUP, value the calibration says, its sd) for each stated calibration of a probe in the
    data (``afe``: the rows' probe flags)."""
    out = []
    for present, (i_off, i_gain) in ((bool((~afe).any()), (0, 1)), (bool(afe.any()), (2, 3))):
        if not present:
            continue
        if setup.offset_sd_V is not None:
            out.append((i_off, 0.0, setup.offset_sd_V))
        if setup.gain_sd is not None:
            out.append((i_gain, 1.0, setup.gain_sd))
    return out


def _calibration_resid(theta, terms) -> np.ndarray:
    """How far a set-up sits from the bench's stated calibration, in standard deviations."""
    return np.array([(theta[i] - v) / sd for i, v, sd in terms])


def column_keys(X):
    return X["arr"] * 100000 + X["col"].astype(int)


# the set-up's parameters, per probe: offset and gain of the pixel probe, then of the AFE probe
SETUP = ("offset_pixel_V", "gain_pixel", "offset_afe_V", "gain_afe")
N_SETUP = len(SETUP)


def _setup(theta, afe, v):
    return np.where(afe, theta[2] + theta[3] * v, theta[0] + theta[1] * v)


def model_fn(name, nom, X, cols=None, uniform=False):
    """(function of full parameter vector -> prediction, parameter specs) for candidate ``name``.

    Specs are (name, lo, hi, scale, prior width or None). ``uniform``: a per-column effect with one
    value of each parameter per array (its uniform counterpart, no prior)."""
    afe = X["afe"]
    if name == "none":
        specs = []
        base = predict(nom, X)

        def f(theta):
            return _setup(theta, afe, base)
    elif name in COLUMN_EFFECTS:
        params, fn = COLUMN_EFFECTS[name]
        if uniform:   # one value per array: the spread tested is the column-to-column one within an array
            idx, n = X["arr"].astype(int), 2
            specs = [(f"{p.name}[{a}]", p.lo, p.hi, p.scale, None) for p in params for a in ("primary", "secondary")]
        else:   # each column its own value (its mismatch, zero-mean prior) on the array's spatial law
            idx, n = np.searchsorted(cols, column_keys(X)), len(cols)
            specs = [(f"{p.name}[{c}]", p.lo, p.hi, p.scale, p.prior) for p in params for c in cols] + \
                [(f"{p.name}_{t}[{a}]", p.lo, p.hi, p.scale, None) for p in params for t in SPATIAL
                 for a in ("primary", "secondary")]
        law = _spatial_law(X, len(params), 0 if uniform else len(params) * n)

        @_memo
        def g(p):
            return predict(nom, X, fn(X, [p[j * n:(j + 1) * n][idx] + law(p, j) for j in range(len(params))]))

        def f(theta):
            return _setup(theta, afe, g(theta[N_SETUP:]))
    else:
        params, fn = plain_effect(name)
        specs = [(p.name, p.lo, p.hi, p.scale, None) for p in params]

        @_memo
        def g(p):
            return predict(nom, X, fn(X, p))

        def f(theta):
            return _setup(theta, afe, g(theta[N_SETUP:]))
    return f, specs


# a column pattern's spatial law across its array (process gradients, a bias or supply line's IR drop fed from one
# end or both): a linear and a parabolic term of the column's position u (-1/2 .. 1/2), each array its own
SPATIAL = ("slope", "bow")


def _spatial_law(X, n_params, start):
    """(p, j) -> the spatial law of column parameter ``j`` at each row: slope 2u + bow (4u^2 - 1/3) of the row's
    array (zero-mean over a uniformly used array), read from ``p[start:]`` (none when ``start`` is 0: the uniform
    counterpart has one value per array and no law)."""
    if not start:
        return lambda p, j: 0.0
    u, a = X["col_pos"], X["arr"].astype(int)
    shapes = (2.0 * u, 4.0 * u * u - 1.0 / 3.0)

    def law(p, j):
        k = start + j * 2 * len(SPATIAL)
        return sum(p[k + 2 * t:k + 2 * t + 2][a] * sh for t, sh in enumerate(shapes))
    return law


def plain_effect(name):
    """(parameters, terms function) of a library effect, or of two at once (``a+b``: parameters
    concatenated, terms added where both act on the same quantity)."""
    parts = name.split("+")
    if len(parts) == 1:
        return effect(name)
    (pa, fa), (pb, fb) = effect(parts[0]), effect(parts[1])
    k = len(pa)

    def fn(X, p):
        ta, tb = fa(X, p[:k]), fb(X, p[k:])
        return {key: ta.get(key, 0.0) + tb.get(key, 0.0) for key in ta.keys() | tb.keys()}
    return tuple(pa) + tuple(pb), fn


def _memo(fn):
    """Remember the last prediction: the set-up's parameters are linear, so the Jacobian's columns for
    them (and the optimiser's set-up-only steps) need no new prediction."""
    last = [None, None]

    def g(p):
        key = np.asarray(p, float).tobytes()
        if last[0] != key:
            last[0], last[1] = key, fn(p)
        return last[1]
    return g


def fit(name, nom, X_train, y_train, sigma, cols=None, setup: SetupBounds = SetupBounds(), uniform=False):
    f, specs = model_fn(name, nom, X_train, cols, uniform)
    s_lo = [-setup.offset_V, 1 - setup.gain_tol] * 2
    s_hi = [setup.offset_V, 1 + setup.gain_tol] * 2
    scales = np.array([1e-3, 1e-2] * 2 + [s[3] for s in specs])
    lo = np.array(s_lo + [s[1] for s in specs]) / scales
    hi = np.array(s_hi + [s[2] for s in specs]) / scales
    plain = name != "none" and name not in COLUMN_EFFECTS
    params = plain_effect(name)[0] if plain else ()
    x0 = np.array([0.0, 1.0] * 2 + ([p.x0 for p in params] if plain else [0.0] * len(specs))) / scales
    x0 = np.clip(x0, lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))

    prior = np.array([np.inf if sp[4] is None else sp[4] for sp in specs])
    has_prior = bool(np.isfinite(prior).any())
    prior_w = np.where(np.isfinite(prior), scales[N_SETUP:] / prior, 0.0)

    cal = calibration_terms(setup, X_train["afe"])

    def resid(u):
        r = [(f(u * scales) - y_train) / sigma]
        if has_prior:
            r.append(u[N_SETUP:] * prior_w)
        if cal:
            r.append(_calibration_resid(u * scales, cal))
        return np.concatenate(r)

    starts = [x0]
    if specs and plain:
        s = x0.copy()   # a second start one typical size away (downwards when the parameter may be negative)
        sign = np.where(np.array([sp[1] for sp in specs]) < 0, -1.0, 1.0)
        s[N_SETUP:] = np.clip(sign * np.array([sp[3] for sp in specs]) / scales[N_SETUP:], lo[N_SETUP:] + 1e-9,
                              hi[N_SETUP:] - 1e-9)
        starts.append(s)
        for j, prm in enumerate(params):
            for v in _scan(f, x0, scales, lo, hi, N_SETUP + j, prm.starts, X_train["afe"], y_train, sigma):
                s = x0.copy()
                s[N_SETUP + j] = v
                starts.append(s)
    best = None
    for s in starts:
        r = least_squares(resid, s, bounds=(lo, hi), x_scale=1.0, method="trf", max_nfev=150)
        if best is None or r.cost < best.cost:
            best = r
    theta = best.x * scales
    n, k = len(y_train), len(theta)
    chi2 = float(np.sum(best.fun[:n] ** 2))
    cal_chi2 = float(np.sum(_calibration_resid(theta, cal) ** 2))
    info = _intervals(best, scales, n, k, lo * scales, hi * scales, theta)
    at = [bool(np.isclose(abs(theta[i] - 1), setup.gain_tol, rtol=1e-3)) for i in (1, 3)] + \
         [bool(np.isclose(abs(theta[i]), setup.offset_V, rtol=1e-3)) for i in (0, 2)]
    return {"theta": theta, "chi2": chi2, "k": k, "n": n, "model": name,
            "bic": chi2 + cal_chi2 + k * math.log(n), "calibration_chi2": cal_chi2,
            "specs": specs, "intervals": info, "setup_at_bound": any(at),
            "setup": dict(zip(SETUP, map(float, theta[:N_SETUP]))), "uniform": uniform}


SCAN_KEEP = 3


def _scan(f, x0, scales, lo, hi, j, grid, afe, y, sigma):
    """The ``SCAN_KEEP`` best of a parameter's grid ``grid`` (scaled values) by the profile chi-square: at each
    value, the other parameters at their start and the set-up's gain and offset per probe solved exactly
    (weighted linear least squares, unbounded). A response with steps in the parameter (readout light: the
    op-amp clamp) has a chi-square with many narrow minima; a local optimiser started a decade away lands in
    the nearest one, a scan finds the basin the data sit in."""
    out = []
    for v in grid:
        u = x0.copy()
        u[j] = np.clip(v / scales[j], lo[j] + 1e-9, hi[j] - 1e-9)
        th = u * scales
        th[:N_SETUP] = (0.0, 1.0, 0.0, 1.0)
        pred = f(th)
        chi2 = 0.0
        for m in (~afe, afe):
            if m.any():
                A = np.stack([np.ones(int(m.sum())), pred[m]], 1) / sigma[m, None]
                coef = np.linalg.lstsq(A, y[m] / sigma[m], rcond=None)[0]
                chi2 += float(np.sum((A @ coef - y[m] / sigma[m]) ** 2))
        out.append((chi2, u[j]))
    return [u for _, u in sorted(out)[:SCAN_KEEP]]


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
    for i in range(N_SETUP, k):
        at_bound = bool(np.isclose(theta[i], lo[i], rtol=0, atol=1e-6 * scales[i])
                        or np.isclose(theta[i], hi[i], rtol=0, atol=1e-6 * scales[i]))
        half = 1.96 * sd[i]
        out.append({"value": float(theta[i]), "ci95": [float(theta[i] - half), float(theta[i] + half)],
                    "identifiable": bool(np.isfinite(cond) and cond < 1e14 and half < abs(theta[i]) and not at_bound),
                    "at_bound": at_bound})
    return out


def prediction_sd(name, nom, X, fitres) -> np.ndarray:
    """Each row's standard uncertainty of the fitted model's effect terms (``nominal.predict_sd``: the
    tabulated responses' own interpolation error) through the set-up's gain; zero for ``none`` and the
    per-column effects."""
    if name == "none" or name in COLUMN_EFFECTS:
        return np.zeros(len(X["afe"]))
    theta = fitres["theta"]
    sd = predict_sd(nom, X, plain_effect(fitres.get("model", name))[1](X, theta[N_SETUP:]))
    return sd * np.abs(np.where(X["afe"], theta[3], theta[1]))


def evaluate(name, nom, X, fitres, cols=None):
    f, _ = model_fn(fitres.get("model", name), nom, X, cols, fitres.get("uniform", False))
    return f(fitres["theta"])
