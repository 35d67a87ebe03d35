"""The Monte Carlo yield of a passing candidate, and the nominal margins it asks for when short.

``verify`` draws ``[verify] mc`` samples at the nominal condition (same seed: the same draws for
every candidate, so the yield is a function of the knobs alone). A spec's yield counts when the
lower end of its Clopper-Pearson interval reaches ``[verify] min_yield`` (``verify`` itself fails
a spec only when the whole interval lies below it: close asks the stricter).

When a spec falls short, its margin target at the nominal condition becomes what a Gaussian
spread of its Monte Carlo margins needs: the pass probability p* at which N = ``[verify] mc`` samples
reach the required number of passes with probability 0.9 (binomial; ``verify``'s sequential Monte
Carlo may stop before N, its samples still give sigma and the mean), z = Phi^-1(p*), and the target
z sigma_m - (mean_m - m_nominal), sigma_m and mean_m the samples' normalised margins and
m_nominal the nominal design's (the offset between the Monte Carlo mean and the mismatch-free
nominal run is kept as measured).
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import ConfigError
from . import margins as mg

#: The chance that N samples of a design at the target show the passes min_yield needs.
ASSURANCE = 0.9


def passes_needed(n: int, min_yield: float, confidence: float) -> int | None:
    """The fewest passes of ``n`` samples whose Clopper-Pearson lower bound reaches ``min_yield``
    (None: not even ``n`` of ``n``)."""
    from ..verify.yields import clopper_pearson
    for k in range(n, -1, -1):
        if clopper_pearson(k, n, confidence)[0] < min_yield:
            return k + 1 if k < n else None
    return 0


def required_pass_probability(n: int, k: int) -> float:
    """The pass probability p at which P(Binomial(n, p) >= k) = ASSURANCE."""
    from scipy.stats import binom
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = (lo + hi) / 2
        if binom.sf(k - 1, n, mid) >= ASSURANCE:
            hi = mid
        else:
            lo = mid
    return hi


def check_samples(design) -> None:
    """``[verify] mc`` can show ``min_yield`` at all (refused before anything runs)."""
    v = design.verify
    if v.min_yield and v.mc and passes_needed(v.mc, v.min_yield, v.confidence) is None:
        from ..verify.yields import clopper_pearson
        lo = clopper_pearson(v.mc, v.mc, v.confidence)[0]
        n = v.mc
        while clopper_pearson(n, n, v.confidence)[0] < v.min_yield and n < 10**6:
            n = int(n * 1.2) + 1
        raise ConfigError(design.source, "verify.mc", v.mc,
                          f"enough samples to show min_yield {100 * v.min_yield:g} %: with all {v.mc} passing the "
                          f"yield interval's lower bound is {100 * lo:.3g} % (at least {n} samples)")
    if v.min_yield and not v.mc:
        raise ConfigError(design.source, "verify.mc", 0, f"Monte Carlo samples (> 0) to show min_yield "
                          f"{100 * v.min_yield:g} %")


def check(design, signoff: dict, nominal, nominal_margins: dict) -> dict:
    """{"ok", "specs": [per spec: yield, interval, ok], "targets": {(spec, nominal): target}, "text"}."""
    v = design.verify
    spec = {s.name: s for s in design.spec}
    rows, targets, short = [], {}, []
    for r in signoff["rows"]:
        y = r.get("yield")
        if not y or not y.get("samples"):
            continue
        lo = y["interval"][0]
        ok = lo >= v.min_yield and r["status"] != "fail"
        rows.append({"spec": r["spec"], "yield": y["yield"], "interval": y["interval"], "samples": y["samples"],
                     "ok": ok})
        if ok or not v.min_yield:
            continue
        short.append(r["spec"])
        s = spec[r["spec"]]
        m = np.array([mg.margin(s, x) for x in signoff["mc_values"][s.name] if x is not None], float)
        m = m[np.isfinite(m)]
        m_nom = nominal_margins.get((s.name, nominal))
        n = max(v.mc, len(m))   # the samples a sign-off may draw (sequential: it may stop before)
        k = passes_needed(n, v.min_yield, v.confidence)
        if m_nom is None or len(m) < 2 or k is None:
            continue
        from scipy.stats import norm
        z = float(norm.ppf(required_pass_probability(n, k)))
        targets[(s.name, nominal)] = max(z * float(m.std(ddof=1)) - (float(m.mean()) - m_nom), 0.0)
    ok = all(r["ok"] for r in rows) or not v.min_yield
    text = "Monte Carlo yield: " + ", ".join(
        f"{r['spec']} {100 * r['yield']:.1f} % [{100 * r['interval'][0]:.1f}, {100 * r['interval'][1]:.1f}]"
        for r in rows) + (f"; min_yield {100 * v.min_yield:g} %" + (" met" if ok else f" not met by "
                                                                     f"{', '.join(short)}") if v.min_yield else "")
    return {"ok": ok, "specs": rows, "targets": targets, "short": short, "text": text,
            "min_yield": v.min_yield, "confidence": v.confidence}


def fmt_targets(targets: dict) -> str:
    return ", ".join(f"{k[0]} at {k[1].label} >= {100 * t:.3g} %" for k, t in targets.items() if math.isfinite(t))
