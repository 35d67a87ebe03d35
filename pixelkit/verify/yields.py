"""Yield statistics of a Monte Carlo run: Clopper-Pearson intervals and margin in sigma.

The Clopper-Pearson ("exact") interval of k passes in n samples is
[B(a/2; k, n - k + 1), B(1 - a/2; k + 1, n - k)] with B the beta quantile and
a = 1 - confidence; it never claims more than the binomial allows (k = n gives
an upper bound of 1 and a lower bound of (a/2)^(1/n), the "rule of three" for
small a). Checked in ``tests/test_verify_yield.py`` against the binomial
distribution summed directly.
"""
from __future__ import annotations

import math

import numpy as np


def clopper_pearson(k: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    from scipy.stats import beta
    a = 1.0 - confidence
    lo = 0.0 if k == 0 else float(beta.ppf(a / 2, k, n - k + 1))
    hi = 1.0 if k == n else float(beta.ppf(1 - a / 2, k + 1, n - k))
    return lo, hi


def margin_sigma(values, lo: float | None, hi: float | None) -> float:
    """Distance of the sample mean to the nearer limit, in sample standard deviations
    (negative: the mean is outside); inf for a spread of zero (the caller refuses that)."""
    v = np.asarray(values, float)
    mu, sd = float(v.mean()), float(v.std(ddof=1)) if v.size > 1 else 0.0
    m = min(x for x in ((mu - lo) if lo is not None else math.inf, (hi - mu) if hi is not None else math.inf))
    return m / sd if sd > 0 else math.copysign(math.inf, m)
