"""The next measurement: operating points that separate candidates the data cannot tell apart.

Each candidate still in the running (the named one and those reported
indistinguishable; two effects named at once and each of them alone; or the
three best when none explains the data) is refitted
on every row; its own prediction is then evaluated over a grid of operating
points a lab can set (array, probe, integration time, light level including
dark frames, extra wait before readout, temperature, read rate, supply). The
expected separation of a point is the smallest difference between any two
candidates' predictions there, in units of the data's noise (one measurement
of the averaged value). The answer lists the best points and, per factor, how
much varying that factor alone (from the data's median operating point)
separates them.
"""
from __future__ import annotations

import itertools

import numpy as np

from .data import Table
from .diagnose import noise
from .fit import SetupBounds, column_keys, evaluate, fit
from .nominal import ARRAYS, features

GRID = {
    "array": list(ARRAYS), "probe": ["pixel", "afe"], "t_int_s": [50e-6, 300e-6, 2e-3],
    "fill": [0.0, 0.1, 0.5], "extra_wait_s": [0.0, 10e-3, 40e-3, 100e-3], "temp_C": [25.0, 45.0, 65.0],
    "f_read_rel": [1.0, 2.0], "dvdd_V": [0.0, -0.15, 0.15],
}


def _grid_table(design, nom, points, cols_seen) -> Table:
    n = len(points)
    arr = [p["array"] for p in points]
    f_design = np.array([getattr(design, a).f_read for a in arr])
    f_read = f_design * np.array([p["f_read_rel"] for p in points])
    t_int = np.array([p["t_int_s"] for p in points])
    q_max = np.array([nom.q_grid[a][-1] for a in arr])
    i_ph = np.array([p["fill"] for p in points]) * q_max / t_int
    col = np.array([cols_seen[a] for a in arr], float)
    return Table({"array": arr, "row": np.zeros(n), "col": col, "i_ph_A": i_ph, "t_int_s": t_int,
                  "t_wait_s": 1.0 / f_read + np.array([p["extra_wait_s"] for p in points]),
                  "temp_C": np.array([p["temp_C"] for p in points]), "probe": [p["probe"] for p in points],
                  "i_ph_prev_A": i_ph, "f_read_Hz": f_read,
                  "vdd_V": design.tech.supply + np.array([p["dvdd_V"] for p in points])}, "plan")


def plan(design, table, nom, result: dict, setup: SetupBounds = SetupBounds(), top: int = 5) -> dict:
    """Operating points that best separate the candidates left by ``result`` (a ``diagnose`` answer)."""
    names = [result["best"]] + list(result["indistinguishable"])
    if len(result.get("effects", [])) == 2:   # two effects at once: what separates each from the other
        names = ["+".join(result["effects"])] + list(result["effects"]) + list(result["indistinguishable"])
    if len(names) < 2:
        ranked = [r["effect"] for r in result["ranking"]]
        names = list(dict.fromkeys(names + ranked))[:3]
    X = features(table, nom, design)
    y = table.num("v_V")
    sigma, _ = noise(table, X, nom)
    w = sigma if np.all(np.isfinite(sigma)) else np.full(y.size, max(np.std(y) * 1e-2, 1e-4))
    cols = np.unique(column_keys(X))
    fits = {n: fit(n, nom, X, y, w, cols, setup) for n in names}
    cols_seen = {a: float(X["col"][X["arr"] == k][0]) if (X["arr"] == k).any() else 0.0
                 for k, a in enumerate(ARRAYS)}
    keys = list(GRID)
    points = [dict(zip(keys, vals)) for vals in itertools.product(*GRID.values())]
    G = _grid_table(design, nom, points, cols_seen)
    XG = features(G, nom, design)
    XG["has_prev"] = X["has_prev"]
    preds = {n: evaluate(n, nom, XG, fits[n], cols) for n in names}
    s0 = float(np.median(w))
    sep = np.full(len(points), np.inf)
    pair_best = {}
    for a, b in itertools.combinations(names, 2):
        d = np.abs(preds[a] - preds[b]) / s0
        sep = np.minimum(sep, d)
        k = int(np.argmax(d))
        pair_best[f"{a} vs {b}"] = {"separation_sigma": float(d[k]), "point": points[k],
                                    "difference_mV": float((preds[a] - preds[b])[k] * 1e3)}
    best_points, seen = [], []
    for k in np.argsort(-sep):   # points whose predictions repeat a listed one add nothing (a factor no model uses)
        sig = np.array([preds[n][k] for n in names])
        if any(np.allclose(sig, o, rtol=0, atol=1e-9) for o in seen):
            continue
        seen.append(sig)
        best_points.append({"point": points[k], "separation_sigma": float(sep[k]),
                            "predictions_V": {n: float(preds[n][k]) for n in names}})
        if len(best_points) == top:
            break
    median = {"array": ARRAYS[int(np.round(np.median(X["arr"])))], "probe": "afe" if X["afe"].mean() >= 0.5 else "pixel",
              "t_int_s": 300e-6, "fill": 0.1, "extra_wait_s": 0.0, "temp_C": 25.0, "f_read_rel": 1.0, "dvdd_V": 0.0}
    levers = []
    for f in keys:
        idx = [i for i, p in enumerate(points) if all(p[g] == median[g] for g in keys if g != f)]
        if idx:
            k = max(idx, key=lambda i: sep[i])
            levers.append({"factor": f, "value": points[k][f], "separation_sigma": float(sep[k])})
    levers.sort(key=lambda r: -r["separation_sigma"])
    return {"candidates": names, "noise_V": s0, "points": best_points, "levers": levers, "pairs": pair_best,
            "separable": bool(best_points and best_points[0]["separation_sigma"] > 3.0),
            "measurements": measurements(result, X, names)}


def measurements(result: dict, X, names) -> list:
    """What the file lacks that would separate the candidates, beyond its operating points: a probe it does
    not have, the bench's calibration, a condition it holds at one value."""
    from .diagnose import POSITION
    out = []
    probes = {"pixel": bool((~X["afe"]).any()), "afe": bool(X["afe"].any())}
    sides = {POSITION.get(n.split("+")[0], "") for n in names}
    if not all(probes.values()) and len(sides) > 1:
        miss = next(p for p, v in probes.items() if not v)
        out.append(f"the {miss} probe: these data have only the {'afe' if miss == 'pixel' else 'pixel'} probe, so an "
                   f"effect before the AFE and one in it move what they show alike (the candidates act at: "
                   + "; ".join(f"{n} {POSITION.get(n.split('+')[0], '?')}" for n in names) + ")")
    if not result.get("calibration", {}).get("stated"):
        out.append("the bench's calibration: a known voltage read through each probe's path, stated with "
                   "--gain-sd / --offset-sd; without it a gain and offset of the chain within the set-up's "
                   "tolerance is the set-up's own (a chain gain at the pixel probe cannot be told from the probe's "
                   "gain)")
    out += [f"vary the {f}" for f in result.get("fixed_conditions", [])]
    return out
