"""Blind check of the diagnosis on virtual measurements whose effect is withheld.

Each case builds a measurement campaign of the reference design the way a lab
would take one (both arrays and probes, eight columns per array, several
integration times, two readout delays, three temperatures, frames after a
different previous frame), adds ONE effect with random parameters drawn from the
ranges below (EFFECTS.md magnitudes, from clearly visible to strong), a random
test set-up gain (1 +- 2 %) and offset (+-20 mV) and measurement noise
(0.5 mV rms), then runs the diagnosis without being told what was added.
Effect-free cases check that the diagnosis answers ``none``.
"""
from __future__ import annotations

import numpy as np

from .data import Table
from .diagnose import diagnose
from .effects import EFFECTS, NAMES, column_shift
from .nominal import ARRAYS, features, predict

NOISE_V = 0.5e-3
ROWS_PER_CASE = 240

# effect -> function(rng) -> parameter vector (SI), drawn from physical ranges
RANGES = {
    "gse": lambda g: [1.0 / g.uniform(300, 3000)],
    "fd_leakage": lambda g: [g.uniform(5e-15, 50e-15), g.uniform(5.0, 9.0)],
    "dark_current": lambda g: [g.uniform(2e-15, 20e-15), g.uniform(5.0, 9.0)],
    "charge_injection": lambda g: [g.choice([-1, 1]) * g.uniform(0.005, 0.03), g.uniform(-0.02, 0.02)],
    "sf_gain": lambda g: [g.uniform(0.03, 0.15)],
    "afe_gain": lambda g: [g.uniform(0.02, 0.1)],
    "coupling": lambda g: [g.uniform(1e7, 1e8)],
    "crosstalk": lambda g: [g.uniform(0.002, 0.01)],
    "column_fpn": lambda g: [g.uniform(0.003, 0.01), g.uniform(0.005, 0.02)],
    "lag": lambda g: [g.uniform(0.02, 0.1)],
}


def campaign(design, nom, rng, n=ROWS_PER_CASE) -> Table:
    """Conditions of one virtual measurement campaign (no ``v_V``)."""
    arr = rng.integers(0, 2, n)
    cols_avail = {0: rng.choice(design.primary.cols, 8, replace=False),
                  1: rng.choice(design.secondary.cols, 8, replace=False)}
    col = np.array([rng.choice(cols_avail[a]) for a in arr])
    row = rng.integers(0, design.primary.rows, n)
    t_int = np.exp(rng.uniform(np.log(50e-6), np.log(2e-3), n))
    frac = rng.uniform(0.03, 0.6, n)
    q_max = np.array([nom.q_grid[ARRAYS[a]][-1] for a in arr])
    i_ph = frac * q_max / t_int
    t_row = np.where(arr == 0, 1 / design.primary.f_read, 1 / design.secondary.f_read)
    t_wait = (row + 1) * t_row + rng.choice([0.0, 10e-3, 40e-3], n)
    temp = rng.choice([25.0, 45.0, 65.0], n)
    prev = i_ph * rng.uniform(0.0, 2.0, n)
    probe = np.where(rng.random(n) < 0.5, "pixel", "afe")
    cols = {"array": [ARRAYS[a] for a in arr], "row": row.astype(float), "col": col.astype(float),
            "i_ph_A": i_ph, "t_int_s": t_int, "t_wait_s": t_wait, "temp_C": temp, "probe": list(probe),
            "i_ph_prev_A": prev}
    return Table(cols, "selftest")


def measure(design, nom, table: Table, effect: str | None, rng, params=None) -> tuple[np.ndarray, dict]:
    """Virtual measured values of ``table`` with ``effect`` (or none) added; returns (v, truth).

    ``params`` fixes the effect's parameters instead of drawing them from ``RANGES``.
    """
    X = features(table, nom, design)
    truth = {"effect": effect or "none"}
    if effect is None:
        v = predict(nom, X)
    elif effect == "column_fpn":
        s_o, s_g = RANGES[effect](rng)
        keys = X["arr"] * 100000 + X["col"].astype(int)
        uk = np.unique(keys)
        o = dict(zip(uk, rng.normal(0, s_o, uk.size)))
        g = dict(zip(uk, rng.normal(0, s_g, uk.size)))
        ov, gv = np.array([o[k] for k in keys]), np.array([g[k] for k in keys])
        v = predict(nom, X) + column_shift(X, nom.gain_afe, ov, gv)
        truth["params"] = {"offset_rms_V": s_o, "gain_rms": s_g}
    else:
        p = np.array(RANGES[effect](rng) if params is None else params)
        v = predict(nom, X, EFFECTS[effect][1](X, p))
        truth["params"] = dict(zip([q.name for q in EFFECTS[effect][0]], p.tolist()))
    gain, offset = 1 + rng.uniform(-0.02, 0.02), rng.uniform(-0.02, 0.02)
    return offset + gain * v + rng.normal(0, NOISE_V, v.size), truth


def run(design, nom, n_per_effect: int = 10, n_clean: int = 20, seed: int = 1) -> dict:
    rng = np.random.default_rng(seed)
    labels = [e for e in NAMES for _ in range(n_per_effect)] + [None] * n_clean
    from ..progress import progress
    cases = []
    for k, eff in enumerate(progress(labels, desc="gap selftest (blind cases)", unit="case")):
        table = campaign(design, nom, rng)
        v, truth = measure(design, nom, table, eff, rng)
        table.columns["v_V"] = v
        d = diagnose(design, table, nom, seed=k)
        cases.append({"truth": truth["effect"], "found": d["best"], "shrink": d["shrink_frac"],
                      "before_V": d["gap_before_rms_V"], "after_V": d["gap_after_rms_V"]})
    names = list(NAMES) + ["none"]
    confusion = {t: {f: 0 for f in names} for t in names}
    for c in cases:
        confusion[c["truth"]][c["found"]] += 1
    eff_cases = [c for c in cases if c["truth"] != "none"]
    clean = [c for c in cases if c["truth"] == "none"]
    return {
        "n_cases": len(cases), "n_effect_cases": len(eff_cases), "n_clean_cases": len(clean),
        "top1_accuracy": float(np.mean([c["found"] == c["truth"] for c in eff_cases])),
        "median_shrink": float(np.median([c["shrink"] for c in eff_cases])),
        "none_on_clean": float(np.mean([c["found"] == "none" for c in clean])) if clean else None,
        "false_attribution_rate": float(np.mean([c["found"] != "none" for c in clean])) if clean else None,
        "confusion": confusion, "noise_V": NOISE_V, "rows_per_case": ROWS_PER_CASE,
        "cases": cases,
    }
