"""Diagnose a measured dataset: where the gap lies, which effect explains it, how far it shrinks."""
from __future__ import annotations

import numpy as np

from .effects import NAMES
from .fit import BIC_MARGIN, HELDOUT_GAIN, _column_keys, evaluate, fit
from .nominal import features
from .where import breakdown

TRAIN_FRACTION = 0.7


def split(n: int, seed: int = 0):
    """Deterministic random split: (train mask, held-out mask)."""
    rng = np.random.default_rng(seed)
    order = rng.permutation(n)
    train = np.zeros(n, bool)
    train[order[: int(round(TRAIN_FRACTION * n))]] = True
    return train, ~train


def _sub(X, m):
    return {k: (v[m] if isinstance(v, np.ndarray) and v.shape == m.shape else v) for k, v in X.items()}


def _rms(x):
    return float(np.sqrt(np.mean(np.square(x)))) if x.size else float("nan")


def diagnose(design, table, nom, seed: int = 0, candidates=NAMES) -> dict:
    return analyse(design, table, nom, seed, candidates)[0]


def analyse(design, table, nom, seed: int = 0, candidates=NAMES):
    """(result, row features, residual of every row against the calibrated nominal model)."""
    X = features(table, nom, design)
    y = table.num("v_V")
    train, test = split(len(y), seed)
    Xtr, Xte = _sub(X, train), _sub(X, test)
    cols = np.unique(_column_keys(X))
    fits = {"none": fit("none", nom, Xtr, y[train])}
    for name in candidates:
        fits[name] = fit(name, nom, Xtr, y[train], cols)
    ranking, preds = [], {}
    for name, fr in fits.items():
        preds[name] = evaluate(name, nom, Xte, fr, cols)
        fr["heldout_rms_V"] = _rms(preds[name] - y[test])
        ranking.append({"effect": name, "heldout_rms_V": fr["heldout_rms_V"], "bic": fr["bic"],
                        "train_rms_V": float(np.sqrt(fr["rss"] / fr["n"])), "n_params": fr["k"] - 2,
                        "params": _params(name, fr), "setup_gain": float(fr["theta"][1]),
                        "setup_offset_V": float(fr["theta"][0])})
    ranking.sort(key=lambda r: r["bic"])
    none = fits["none"]
    top = next((r["effect"] for r in ranking if r["effect"] != "none"), "none")
    cand = fits[top]
    clear = (none["bic"] - cand["bic"] > BIC_MARGIN
             and cand["heldout_rms_V"] <= (1 - HELDOUT_GAIN) * none["heldout_rms_V"])
    best = top if clear else "none"
    before, after = none["heldout_rms_V"], fits[best]["heldout_rms_V"]
    resid_none = y - evaluate("none", nom, X, none)
    pred_best, pred_none = preds[best], preds["none"]
    result = {
        "n_rows": int(len(y)), "n_train": int(train.sum()), "n_heldout": int(test.sum()),
        "gap_before_rms_V": before, "gap_after_rms_V": after,
        "gap_before_max_V": float(np.max(np.abs(pred_none - y[test]))),
        "gap_after_max_V": float(np.max(np.abs(pred_best - y[test]))),
        "shrink_frac": 1.0 - after / before if before > 0 else 0.0,
        "best": best, "runner_up": top if best == "none" else None,
        "ranking": ranking,
        "regions": _regions(Xte, y[test], pred_none, pred_best),
        "where": breakdown(X, resid_none),
        "surrogate_error": nom.error,
    }
    return result, X, resid_none


def _params(name, fr):
    if name == "column_fpn":
        vals = fr["theta"][2:]
        half = len(vals) // 2
        return {"offset_rms_V": float(np.std(vals[:half])), "gain_rms": float(np.std(vals[half:])),
                "n_columns": half}
    return {spec[0]: iv for spec, iv in zip(fr["specs"], fr["intervals"])}


def _regions(X, y, before, after):
    out = []
    for label, m in (("pixel probe", ~X["afe"]), ("afe probe", X["afe"]), ("primary", X["arr"] == 0),
                     ("secondary", X["arr"] == 1)):
        if m.any():
            out.append({"region": label, "n": int(m.sum()), "rms_before_V": _rms(before[m] - y[m]),
                        "rms_after_V": _rms(after[m] - y[m])})
    return out
