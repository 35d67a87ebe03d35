"""Where the measured data leave the nominal model: residuals by stage and condition, with significance."""
from __future__ import annotations

import numpy as np

from .pvalue import anova, pearson, ttest_zero

P_SIGNIFICANT = 1e-3


def _bins(x, n=4):
    """Quantile bins of a continuous variable, as (label, mask) pairs."""
    edges = np.unique(np.quantile(x, np.linspace(0, 1, n + 1)))
    if edges.size < 2:
        return [(f"{edges[0]:.3g}", np.ones_like(x, bool))]
    out = []
    for k, (a, b) in enumerate(zip(edges, edges[1:])):
        m = (x >= a) & ((x <= b) if k == edges.size - 2 else (x < b))
        out.append((f"[{a:.3g}, {b:.3g}]", m))
    return out


def breakdown(X, resid) -> list[dict]:
    """Mean residual per group of every factor; t-test against zero; trends by correlation."""
    factors = {
        "probe": [("afe", X["afe"]), ("pixel", ~X["afe"])],
        "subpixel": [("primary", X["arr"] == 0), ("secondary", X["arr"] == 1)],
        "signal_V": _bins(X["signal"]), "t_int_s": _bins(X["t_int"]), "t_wait_s": _bins(X["t_wait"]),
        "row": _bins(X["row"]), "temp_C": [(f"{t:g}", X["T"] == t) for t in np.unique(X["T"])][:12]
        if np.unique(X["T"]).size <= 12 else _bins(X["T"]),
        "i_ph_A": _bins(X["i"]),
    }
    rows = []
    for factor, groups in factors.items():
        for label, m in groups:
            r = resid[m]
            if r.size < 3:
                continue
            p = ttest_zero(r)
            rows.append({"factor": factor, "level": label, "n": int(r.size), "mean_V": float(r.mean()),
                         "std_V": float(r.std(ddof=1)), "p": float(p), "significant": bool(p < P_SIGNIFICANT)})
    keys = X["arr"] * 100000 + X["col"].astype(int)
    col_means = [(k, resid[keys == k]) for k in np.unique(keys)]
    col_means = [(k, r) for k, r in col_means if r.size >= 3]
    if len(col_means) >= 3:
        groups = [r for _, r in col_means]
        p = anova(groups)
        rows.append({"factor": "column", "level": f"{len(groups)} columns (ANOVA)", "n": int(sum(map(len, groups))),
                     "mean_V": float(np.std([g.mean() for g in groups])), "std_V": float(np.std(resid)),
                     "p": float(p), "significant": bool(p < P_SIGNIFICANT)})
    stages = (("all rows", np.ones_like(X["afe"], bool)), ("pixel probe", ~X["afe"]), ("afe probe", X["afe"]))
    for var in ("signal", "t_int", "t_wait", "T", "i", "row"):
        for stage, m in stages:
            x, r_ = X[var][m], resid[m]
            if x.size < 5 or np.ptp(x) == 0 or np.ptp(r_) == 0:
                continue
            u = (x - x.mean()) / np.ptp(x)   # scaled to a span of 1: pA and ms fit as well as volts
            r, p = pearson(u, r_)
            rows.append({"factor": f"trend vs {var}", "level": f"{stage}: r = {r:+.2f}", "n": int(x.size),
                         "mean_V": float(np.polyfit(u, r_, 1)[0]), "std_V": float(np.std(r_)),
                         "p": float(p), "significant": bool(p < P_SIGNIFICANT)})
    rows.sort(key=lambda r: (not r["significant"], -abs(r["mean_V"])))
    return rows
