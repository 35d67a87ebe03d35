"""Regression of a design's measured figures against a stored baseline.

A baseline is a JSON file ``{"design": ..., "figures": {name: {"value", "tol_rel", "tol_abs"}}}``.
A figure has changed when |new - old| > max(tol_rel |old|, tol_abs).
"""
from __future__ import annotations

import json
from pathlib import Path

from .errors import ConfigError
from .fileio import write_atomic
from .readfile import FileRefused, read_text

#: figure name -> (relative tolerance, absolute tolerance in the figure's SI unit)
TOLERANCES = {
    "primary.i_mid_A": (0.01, 1e-12),
    "secondary.i_5pct_A": (0.01, 0.2e-12),
    "primary.swing_V": (0.005, 1e-3),
    "secondary.swing_V": (0.005, 1e-3),
    "primary.pedestal_V": (0.0, 2e-3),
    "secondary.pedestal_V": (0.0, 2e-3),
    "ratio": (0.01, 0.0),
    "model_vs_spice.max_err_frac": (0.0, 0.01),
    "fig_a1.max_diff_frac": (0.0, 0.005),
}


def tolerances(result: dict) -> dict:
    """The dual pixel's TOLERANCES, or those of the result's pixel family (pixelkit/family.py)."""
    if result.get("family"):
        from .family import regress_tolerances
        return regress_tolerances(result["family"])
    return TOLERANCES


def figures(result: dict) -> dict:
    out = {}
    for name in tolerances(result):
        node = result
        for part in name.split("."):
            node = node[part]
        out[name] = float(node)
    return out


def make_baseline(design_name: str, result: dict) -> dict:
    return {"design": design_name,
            "figures": {k: {"value": v, "tol_rel": tolerances(result)[k][0], "tol_abs": tolerances(result)[k][1]}
                        for k, v in figures(result).items()}}


def load_baseline(path: Path) -> dict:
    try:
        data = json.loads(read_text(path, "baseline", "json"))
        figs = data["figures"]
        assert all({"value", "tol_rel", "tol_abs"} <= set(f) for f in figs.values())
    except FileRefused as exc:
        if not exc.missing:
            raise
        raise ConfigError(str(path), "baseline", str(path), "an existing baseline (create it with --update)") from None
    except (ValueError, KeyError, AssertionError, TypeError):
        raise ConfigError(str(path), "baseline", "(unreadable)", "a baseline JSON written by 'pixelkit regress --update'") from None
    return data


#: Earlier names of figures (a baseline written before the rename compares with the new name).
RENAMED = {"primary.dark_signal_V": "primary.pedestal_V", "secondary.dark_signal_V": "secondary.pedestal_V"}


def compare(baseline: dict, result: dict) -> list[dict]:
    """Every figure with old, new, change and whether it is beyond tolerance."""
    new = figures(result)
    rows = []
    for name, ref in baseline["figures"].items():
        name = RENAMED.get(name, name)
        if name not in new:
            rows.append({"figure": name, "old": ref["value"], "new": None, "changed": True})
            continue
        old, val = ref["value"], new[name]
        tol = max(ref["tol_rel"] * abs(old), ref["tol_abs"])
        rows.append({"figure": name, "old": old, "new": val, "delta": val - old, "tolerance": tol,
                     "changed": abs(val - old) > tol})
    return rows


def save_baseline(path: Path, baseline: dict) -> None:
    write_atomic(path, json.dumps(baseline, indent=1) + "\n")
