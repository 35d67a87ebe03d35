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


#: Samples per stage of a sequential Monte Carlo: the yields are looked at after every STAGE samples.
STAGE = 20


def looks(n_max: int) -> list[int]:
    """The sample counts at which a sequential Monte Carlo of at most ``n_max`` samples looks at
    its yields: every ``STAGE`` samples, and at ``n_max``."""
    return sorted({*range(STAGE, n_max, STAGE), n_max}) if n_max > 0 else []


def stop_confidence(confidence: float, n_max: int) -> float:
    """The level of the interval that decides an early stop: ``confidence`` shared out over the
    looks (Bonferroni), so that stopping at whichever look comes first errs no more often than
    one interval at ``confidence`` does."""
    return 1.0 - (1.0 - confidence) / max(1, len(looks(n_max)))


def decided(k: int, n: int, min_yield: float, confidence: float, n_max: int) -> str | None:
    """"above" or "below" when the yield of ``k`` passes in ``n`` samples lies wholly at or above
    ``min_yield`` or wholly below it at the stopping level (``stop_confidence``), else None.
    With ``min_yield`` 0 (yield reported, not checked) every yield lies at or above it."""
    if n == 0:
        return None
    lo, hi = clopper_pearson(k, n, stop_confidence(confidence, n_max))
    if lo >= min_yield:
        return "above"
    return "below" if hi < min_yield else None
