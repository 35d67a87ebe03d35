"""The few p-values the diagnosis needs, from scipy.special's distribution functions.

``scipy.stats`` costs 0.6 s to import on a quiet core (1.7 s under load): a sixth of a
cold ``gap diagnose``. These are the textbook forms scipy.stats evaluates with the
same special functions (``tests/test_gap.py::test_pvalues_match_scipy_stats`` compares
them with scipy.stats itself on random data).
"""
from __future__ import annotations

import numpy as np
from scipy import special


def chi2_sf(x, k) -> float:
    """P(chi-square(k) > x)."""
    return float(special.chdtrc(k, max(float(x), 0.0)))


def chi2_isf(p, k) -> float:
    """The x with P(chi-square(k) > x) = p."""
    return float(special.chdtri(k, p))


def _t_two_sided(t, df) -> float:
    return float(2.0 * special.stdtr(df, -abs(t))) if np.isfinite(t) else (0.0 if not np.isnan(t) else float("nan"))


def ttest_zero(r) -> float:
    """Two-sided p-value of a one-sample t-test of mean 0 (nan for constant data, as scipy.stats)."""
    r = np.asarray(r, float)
    sd = r.std(ddof=1)
    if sd == 0:
        return float("nan")
    return _t_two_sided(r.mean() / (sd / np.sqrt(r.size)), r.size - 1)


def anova(groups) -> float:
    """p-value of a one-way ANOVA (are the groups' means equal?)."""
    groups = [np.asarray(g, float) for g in groups]
    n, k = sum(g.size for g in groups), len(groups)
    mean = np.concatenate(groups).mean()
    ssb = sum(g.size * (g.mean() - mean) ** 2 for g in groups)
    ssw = sum(((g - g.mean()) ** 2).sum() for g in groups)
    if ssw == 0:
        return float("nan")
    return float(special.fdtrc(k - 1, n - k, (ssb / (k - 1)) / (ssw / (n - k))))


def pearson(x, y) -> tuple[float, float]:
    """(r, two-sided p-value of r = 0)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    r = float(np.clip(np.corrcoef(x, y)[0, 1], -1.0, 1.0))
    df = x.size - 2
    if abs(r) == 1.0:
        return r, 0.0
    return r, _t_two_sided(r * np.sqrt(df / (1.0 - r * r)), df)
