"""Blind check of the diagnosis, in two kinds reported separately.

*Surrogate-generated* cases (``run``): a lab-like campaign of the reference
design (both arrays and probes, eight columns per array, integration times,
readout delays, three temperatures, previous frames, three supply levels and
read rates), ONE effect added through the effect library with parameters drawn
from ``RANGES`` (typical magnitudes of a 0.35 um 3.3 V pixel, from barely visible to strong), a test
set-up gain (1 +- 2 %) and offset (+- 20 mV) and measurement noise stated in
``v_std_V`` / ``n_avg``. These check the fitter's arithmetic and identifiability
only: the data come from the same effect functions.

*SPICE-generated* cases (``silicon``): the committed virtual-silicon files,
made by ngspice with effects inserted as circuit elements; the stronger check.
"""
from __future__ import annotations

import numpy as np

from .data import Table
from .diagnose import diagnose
from .effects import COLUMN_EFFECTS, EFFECTS, NAMES
from .nominal import ARRAYS, features, predict

NOISE_V = 0.6e-3      # per-frame temporal noise written in v_std_V
N_AVG = 4
ROWS_PER_CASE = 240


def _u(g, lo, hi):
    return g.uniform(lo, hi)


# effect -> function(rng) -> parameter vector (SI), drawn from physical ranges (typical 0.35 um magnitudes)
RANGES = {
    "gse": lambda g: [1.0 / _u(g, 300, 10000), 1.0 / _u(g, 300, 10000), _u(g, 0.0, 0.3)],   # GSE 300:1 .. 1e4:1
    "fd_leakage": lambda g: [_u(g, 5e-17, 5e-16), _u(g, 0.0, 0.6), _u(g, -0.05, 0.1), _u(g, 0.0, 0.4)],  # 10 - 100 mV/s
    "dark_current": lambda g: (lambda v: v + v[2:4])(   # 1.3 - 13 ke-/s (primary); the perimeter's law the area's
        [_u(g, 2e-16, 2e-15), _u(g, 0.0, 1.0), _u(g, 0.0, 0.6), _u(g, -0.05, 0.1), _u(g, 0.0, 0.4)]),
    "charge_injection": lambda g: [_u(g, 3e-18, 3e-17), g.choice([-1, 1]) * _u(g, 0.3e-15, 3e-15),
                                   _u(g, 0.0, 0.3e-15)],                      # RST-FD, p1-vm, the switch on FD
    # (the drifts with temperature the fit may use, sf_gain's p[2:4] and sf_strength's small-signal gain
    # p[4:6], are drawn at their textbook 0: the library's edit as it was when these ranges were set)
    "sf_gain": lambda g: [1.0 / _u(g, 6e6, 2.5e7), _u(g, -0.3, 0.3), 0.0, 0.0],   # 3 - 10 % chain gain loss
    "column_load": lambda g: [g.choice([-1, 1]) * _u(g, 0.05, 0.2)],          # load current 5 - 20 % off
    "sf_strength": lambda g: [float(np.exp(_u(g, np.log(0.6), np.log(1.6)))) - 1, _u(g, -0.3e-15, 0.8e-15),
                              _u(g, -0.03, 0.03), _u(g, -0.2, 0.2), 0.0, 0.0],  # SF W x 0.6 - 1.6, L
    "afe_gain": lambda g: [_u(g, 0.01, 0.05), 0.0, 0.0],                      # C13 larger
    "readout_light": None,                                                   # scaled to the campaign (below)
    "crosstalk": lambda g: [_u(g, 0.003, 0.03)],
    "column_pixel": lambda g: [_u(g, 0.02, 0.08)],                            # load current mismatch (sd)
    "column_afe": lambda g: [_u(g, 0.003, 0.01), _u(g, 0.3e-15, 1.5e-15)],    # C11 and p1 coupling (sd)
    "lag": lambda g: [_u(g, 0.01, 0.05), _u(g, 0.5, 20.0)],
    "supply": lambda g: [g.choice([-1, 1]) * _u(g, 0.01, 0.05), g.choice([-1, 1]) * _u(g, 0.01, 0.05)],
    "settling": None,                                                        # scaled to the design's read rate
}


def readout_light_params(X, g, c13):
    """AFE and output-stage terms of 1 - 10 mV at the campaign's brightest AFE row, random sign and site
    (the AFE's by its charge-balance term I t_float / C13, I = junction area x irradiance)."""
    site = g.choice(["afe", "out", "both"])
    x_afe = np.quantile((X["J"] * X["t_float"])[X["afe"]], 0.9) / c13
    x_out = np.quantile(X["J"], 0.9)
    k_afe = g.choice([-1, 1]) * _u(g, 1e-3, 1e-2) / x_afe if site != "out" else 0.0
    k_out = g.choice([-1, 1]) * _u(g, 1e-3, 1e-2) / x_out if site != "afe" else 0.0
    return [k_afe, k_out]


def settling_params(X, g):
    """tau giving a 0.1 - 1 % signal loss at the design's read rate."""
    eps = np.exp(_u(g, np.log(1e-3), np.log(1e-2)))
    return [0.3 / (float(np.max(X["f_design"])) * -np.log(eps))]


def campaign(design, nom, rng, n=ROWS_PER_CASE, vary_setup=True) -> Table:
    """Conditions of one virtual measurement campaign (no ``v_V``)."""
    arr = rng.integers(0, 2, n)
    cols_avail = {0: rng.choice(design.primary.cols, 8, replace=False),
                  1: rng.choice(design.secondary.cols, 8, replace=False)}
    col = np.array([rng.choice(cols_avail[a]) for a in arr])
    row = rng.integers(0, design.primary.rows, n)
    t_int = np.exp(rng.uniform(np.log(50e-6), np.log(2e-3), n))
    frac = np.where(rng.random(n) < 0.1, 0.0, rng.uniform(0.03, 0.6, n))    # some dark frames
    q_max = np.array([nom.q_grid[ARRAYS[a]][-1] for a in arr])
    i_ph = frac * q_max / t_int
    f_design = np.where(arr == 0, design.primary.f_read, design.secondary.f_read)
    f_read = f_design * (rng.choice([1.0, 1.5, 2.0], n) if vary_setup else 1.0)
    t_wait = (row + 1) / f_read + rng.choice([0.0, 10e-3, 40e-3], n)
    temp = rng.choice([25.0, 45.0, 65.0], n)
    prev = i_ph * rng.uniform(0.0, 2.0, n)
    probe = np.where(rng.random(n) < 0.5, "pixel", "afe")
    cols = {"array": [ARRAYS[a] for a in arr], "row": row.astype(float), "col": col.astype(float),
            "i_ph_A": i_ph, "t_int_s": t_int, "t_wait_s": t_wait, "temp_C": temp, "probe": list(probe),
            "i_ph_prev_A": prev, "v_std_V": np.full(n, NOISE_V), "n_avg": np.full(n, float(N_AVG))}
    if vary_setup:
        cols["vdd_V"] = design.tech.supply + rng.choice([-0.15, 0.0, 0.15], n)
        cols["f_read_Hz"] = f_read
    return Table(cols, "selftest")


def measure(design, nom, table: Table, effect: str | None, rng, params=None) -> tuple[np.ndarray, dict]:
    """Virtual measured values of ``table`` with ``effect`` (or none) added; returns (v, truth).

    ``params`` fixes the effect's parameters instead of drawing them from ``RANGES``.
    """
    X = features(table, nom, design)
    truth = {"effect": effect or "none"}
    if effect is None:
        v = predict(nom, X)
    elif effect in COLUMN_EFFECTS:
        s = RANGES[effect](rng) if params is None else params
        kinds, fn = COLUMN_EFFECTS[effect]
        keys = X["arr"] * 100000 + X["col"].astype(int)
        uk = np.unique(keys)
        draws = [dict(zip(uk, rng.normal(0, sd, uk.size))) for sd in s]
        v = predict(nom, X, fn(X, [np.array([d[k] for k in keys]) for d in draws]))
        truth["params"] = {f"{k.name}_sd": sd for k, sd in zip(kinds, s)}
    else:
        if params is not None:
            p = np.array(params)
        elif effect == "readout_light":
            p = np.array(readout_light_params(X, rng, nom.c13))
        elif effect == "settling":
            p = np.array(settling_params(X, rng))
        else:
            p = np.array(RANGES[effect](rng))
        v = predict(nom, X, EFFECTS[effect][1](X, p))
        truth["params"] = dict(zip([q.name for q in EFFECTS[effect][0]], p.tolist()))
    gain, offset = 1 + rng.uniform(-0.02, 0.02), rng.uniform(-0.02, 0.02)
    sd = table.num("v_std_V") / np.sqrt(table.num("n_avg"))
    return offset + gain * v + rng.normal(0, 1, v.size) * sd, truth


def _right(c) -> bool:
    return c["found"] in c.get("accept", [c["truth"]])


def score(cases: list) -> dict:
    """Top-1, none-on-clean and not-explained rates of diagnosed cases (truth, found, explained; a case's
    ``accept``: the names that count as right, default its truth; two effects: ``a+b``, both named)."""
    names = sorted({c["truth"] for c in cases} | {c["found"] for c in cases})
    confusion = {t: {f: 0 for f in names} for t in names}
    for c in cases:
        confusion[c["truth"]][c["found"]] += 1
    lib = [c for c in cases if c["truth"] not in ("none", "out_of_library")]
    clean = [c for c in cases if c["truth"] == "none"]
    ool = [c for c in cases if c["truth"] == "out_of_library"]

    def rate(xs, fn):
        return float(np.mean([fn(c) for c in xs])) if xs else None
    return {
        "n_cases": len(cases), "n_effect_cases": len(lib), "n_clean_cases": len(clean),
        "n_out_of_library_cases": len(ool),
        "top1_accuracy": rate(lib, _right),
        "explained_when_right": rate([c for c in lib if _right(c)], lambda c: c["explained"] is True),
        "median_shrink": float(np.median([c["shrink"] for c in lib])) if lib else None,
        "none_on_clean": rate(clean, lambda c: c["found"] == "none"),
        "false_attribution_rate": rate(clean, lambda c: c["found"] != "none"),
        "not_explained_on_out_of_library": rate(ool, lambda c: c["explained"] is False),
        "per_effect_top1": {e: rate([c for c in lib if c["truth"] == e], _right)
                            for e in sorted({c["truth"] for c in lib})},
        "confusion": confusion,
    }


def bench(t: dict) -> str:
    """A case's bench (``truth.json`` entry or a diagnosed case): ``calibrated`` for the cases added after the
    first 151, which carry their campaign and state their calibration (``silicon.stated_setup``), else ``free``."""
    return t.get("bench") or ("calibrated" if "campaign" in t else "free")


def stratum(t: dict) -> str:
    """A case's stratum: its inserted circuit, its campaign and its bench."""
    return f"{t['circuit']}@{t.get('campaign', 'lab')}/{bench(t)}"


def population(truths: dict) -> dict:
    """Cases per stratum in the committed set."""
    out = {}
    for t in truths.values():
        out[stratum(t)] = out.get(stratum(t), 0) + 1
    return out


def stratified_sample(truths: dict, fraction: float, other: float = 0.25, minimum: int = 3) -> list:
    """Case ids: per kind (``circuit`` in truth.json), the first ceil(fraction x its count) cases of an
    in-library kind (``other`` for effect-free and out-of-library kinds), at least ``minimum`` (cases of a
    kind are independent draws, so the first ones are a random sample of it)."""
    by = {}
    for cid, t in truths.items():
        by.setdefault((stratum(t), t["effect"] in ("none", "out_of_library")), []).append(cid)
    out = []
    for (_, rest), ids in by.items():
        out += ids[:min(len(ids), max(minimum, int(np.ceil((other if rest else fraction) * len(ids)))))]
    return out


def right_population(lib: list, population: dict) -> dict:
    """Right-named cases per stratum in the whole set, estimated from the sample's top-1 of that stratum
    (the population ``stratified_rate`` weighs a rate over right-named cases by)."""
    out = {}
    for k in {stratum(c) for c in lib}:
        xs = [_right(c) for c in lib if stratum(c) == k]
        out[k] = max(population[k] * sum(xs) / len(xs), sum(xs))
    return out


def stratified_rate(cases: list, population: dict, ok) -> dict:
    """Estimate, over the whole committed set, the rate of ``ok`` on the diagnosed sample ``cases``
    (stratified by ``stratum``; ``population``: cases per stratum in the set), with its 95 % interval
    (normal approximation, finite-population correction per stratum). ``half_width_worst``: the interval's
    half width were every stratum's rate 0.5 (what the sample's size guarantees whatever the outcome)."""
    strata = {}
    for c in cases:
        strata.setdefault(stratum(c), []).append(bool(ok(c)))
    n_all = sum(population[k] for k in strata)
    est, var, worst = 0.0, 0.0, 0.0
    for k, xs in strata.items():
        w, n, big_n = population[k] / n_all, len(xs), population[k]
        p = float(np.mean(xs))
        est += w * p
        if n > 1:
            var += w ** 2 * (1 - n / big_n) * p * (1 - p) / (n - 1)
            worst += w ** 2 * (1 - n / big_n) * 0.25 / (n - 1)
    half = 1.96 * float(np.sqrt(var))
    return {"rate": est, "ci95": [est - half, est + half], "half_width": half, "n": len(cases),
            "population": n_all, "half_width_worst": 1.96 * float(np.sqrt(worst))}


def run(design, nom, n_per_effect: int = 10, n_clean: int = 20, seed: int = 1, rows: int = ROWS_PER_CASE) -> dict:
    rng = np.random.default_rng(seed)
    labels = [e for e in NAMES if e in RANGES for _ in range(n_per_effect)] + [None] * n_clean
    cases = []
    for k, eff in enumerate(labels):
        table = campaign(design, nom, rng, n=rows)
        v, truth = measure(design, nom, table, eff, rng)
        table.columns["v_V"] = v
        d = diagnose(design, table, nom, seed=k)
        cases.append({"truth": truth["effect"], "found": d["best"], "explained": d["explained"],
                      "indistinguishable": d["indistinguishable"], "shrink": d["shrink_frac"],
                      "before_V": d["gap_before_rms_V"], "after_V": d["gap_after_rms_V"]})
    out = score(cases)
    out.update({"kind": "surrogate-generated", "noise_V": NOISE_V, "n_avg": N_AVG,
                "rows_per_case": rows, "cases": cases})
    return out
