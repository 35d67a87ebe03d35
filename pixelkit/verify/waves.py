"""A spec down to its waveform: the decks its measurement ran at the spec's worst condition and at
nominal, the nodes it read and the readings it took (sample instants, levels read).

The measurement is run again under ``measure.recording()``: the same decks (the simulation cache
hands them back without simulating when the sign-off ran them), and the marks are the readings
the measurement's own code took (``measure._mark`` at each reading site), not a re-derivation.
Each deck's vectors are written as an ngspice raw file beside the report (``pixelkit waves``
opens them; so does ngspice's ``load``).
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from . import conditions, measure
from .figures import FIGURES

#: per figure stem: the decks (titles) to show and which node of each subpixel; figures whose
#: measurement has no transient of its own (read noise: two operating points; power; settling,
#: which runs the frame model) have no waveform view.
VIEWS = {
    "conversion_gain": (("vfy_dark", "vfy_small"), "col"),
    "pd_conversion_gain": (("vfy_dark", "vfy_small"), "pd"),
    "swing": (("vfy_dark", "vfy_sat"), "col"),
    "full_well": (("vfy_dark", "vfy_sat"), "col"),
    "dynamic_range": (("vfy_dark", "vfy_sat"), "col"),
    "image_lag": (("vfy_lag_dark", "vfy_lag_sat"), "col"),
    "gse": (("vfy_gse_l0", "vfy_gse_l1", "vfy_gse_d0", "vfy_gse_d1"), "col"),
    "pd_dark_drop": (("vfy_dark_p", "vfy_dark_s"), "pd"),
    "storage_light": (("vfy_sto_dark_primary", "vfy_sto_lit_primary", "vfy_sto_dark_secondary",
                       "vfy_sto_lit_secondary"), "col"),
    "criterion": (("vfy_mid_lo", "vfy_mid_hi"), "col"),
    "afe_gain_error": (("vfy_afe",), "out"),
}
#: at most this many points per trace in the page (the raw file keeps every point)
POINTS = 4000


def view_of(figure: str):
    """(decks, node kind, subpixel kinds) of ``figure``, or None when it has no waveform view."""
    for stem, (decks, node) in VIEWS.items():
        if figure == stem or figure.startswith(stem + "_"):
            kind = figure[len(stem) + 1:] or None
            if stem == "pd_dark_drop":
                decks = tuple(d for d in decks if d.endswith("_" + kind[0]))
            if stem == "storage_light":
                decks = tuple(d for d in decks if d.endswith("_" + kind))
            kinds = ("primary", "secondary") if stem == "criterion" else ((kind,) if kind else ())
            return decks, node, kinds
    return None


def _node(node_kind: str, kind: str | None, deck: str) -> str:
    if node_kind == "out":
        return "out"
    if deck.startswith("vfy_dark_"):
        return "pd"
    if node_kind == "pd":
        return "x1.xp.pd" if kind == "primary" else "x1.xs0.pd"
    return "col_p" if kind == "primary" else "col_s0"


def _thin(t: np.ndarray, v: np.ndarray) -> tuple[list, list]:
    step = max(1, int(np.ceil(t.size / POINTS)))
    idx = np.unique(np.r_[np.arange(0, t.size, step), t.size - 1])
    return t[idx].tolist(), v[idx].tolist()


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.+-]+", "_", text).strip("_")


def spec_waves(design, row: dict, folder: Path, rel: str, backend: str = "batch") -> dict | None:
    """The waveform view of sign-off row ``row`` (its worst condition against nominal), the raw files
    written under ``folder`` (named in the result relative to the report: ``rel``); None when the
    figure has no transient view or the spec was not measured."""
    from ..spice.waveforms import write_waveforms
    fig = FIGURES[row["figure"]]
    view = view_of(fig.name)
    if view is None or not row.get("worst_condition"):
        return None
    decks, node_kind, kinds = view
    w = row["worst_condition"]
    worst = conditions.Condition(w["corner"], w["temperature_C"] + 273.15, w["supply_dev"])
    nominal = conditions.nominal(design)
    out = {"spec": row["spec"], "figure": fig.name, "unit": row.get("unit", ""), "worst": worst.label,
           "nominal": nominal.label, "traces": [], "marks": [], "files": []}
    group = fig.group.split("+")[0]
    for role, cond in (("worst", worst), ("nominal", nominal)):
        if role == "nominal" and cond == worst:
            out["note"] = "the worst condition is the nominal one"
            break
        with measure.recording() as rec:
            measure.run_group(group, conditions.at(design, cond), None, backend)
        for deck in decks:
            r = rec["results"].get(deck)
            if r is None:
                continue
            nodes = [_node(node_kind, k, deck) for k in (kinds or (None,))]
            name = f"{_slug(row['spec'])}_{role}_{_slug(cond.label)}_{deck}.raw"
            write_waveforms(r, Path(folder) / name, [f"v({n})" for n in dict.fromkeys(nodes)])
            out["files"].append(f"{rel}/{name}")
            for n in dict.fromkeys(nodes):
                t, v = _thin(r.time, r[f"v({n})"])
                out["traces"].append({"name": f"{deck} {n} @ {role} ({cond.label})", "role": role, "deck": deck,
                                      "node": n, "condition": cond.label, "t": t, "v": v})
                out["marks"] += [{**m, "role": role, "condition": cond.label} for m in rec["marks"]
                                 if m["deck"] == deck and m["node"] == n]
    return out
