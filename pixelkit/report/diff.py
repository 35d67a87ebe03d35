"""The revision diff: what changed between two report folders, by how much, pass/fail.

- checked figures (``summary.json``): old, new, change, the tolerance the section stated
  (|new - old| > max(tol_rel |old|, tol_abs) is a failure), figures added or removed;
- table values (``tables.json``): every cell that differs (numbers by relative change,
  text when it differs), rows added or removed; reported, not failing;
- netlists (``netlists/*.cir``): every generated netlist whose text changed, with the
  changed lines;
- figures (pictures): every picture file whose bytes changed;
- design parameters (``design.json``): every field that differs (this is what names the
  changed device size);
- specs (``data_signoff.json``, the sign-off section): each spec's worst value and margin in
  both revisions, ranked by how much of its margin the revision used (in % of the limit).

Pass / fail: a design with specs fails the diff on its specs, when one fails in this revision
that did not in the baseline (newly failing, or a new spec that fails); checked figures that
moved are listed, ranked, and do not fail it (``regress`` keeps the strict any-move
semantics). A design without specs fails when a checked figure moved beyond its tolerance.
"""
from __future__ import annotations

import difflib
import json
import math
from pathlib import Path

from ..errors import ConfigError
from ..readfile import FileRefused, read_text, sha256_file

PICTURES = (".png", ".svg", ".jpg")


def load_report(folder: Path) -> dict:
    folder = Path(folder)
    try:
        summary = json.loads(read_text(folder / "summary.json", "--baseline", "report"))
        summary["checked"]  # noqa: B018 - must exist
    except FileRefused as exc:
        if not exc.missing:   # there, but a pipe, a device, too large...
            raise
        raise ConfigError("", "--baseline", str(folder), "a report folder written by 'pixelkit report' "
                          "(it has no summary.json)") from None
    except (ValueError, KeyError, TypeError):
        raise ConfigError(str(folder / "summary.json"), "checked", "(unreadable)",
                          "a summary.json written by 'pixelkit report'") from None
    return {"folder": str(folder), "summary": summary,
            "tables": _json(folder / "tables.json"), "design": _json(folder / "design.json"),
            "signoff": _json(folder / "data_signoff.json").get("rows") or [],
            "netlists": {p.name: read_text(p, "--baseline", "report")
                         for p in sorted((folder / "netlists").glob("*.cir"))},
            "pictures": {p.name: sha256_file(p, "--baseline", "report")
                         for p in sorted(folder.iterdir()) if p.suffix in PICTURES}}


def _json(path: Path) -> dict:
    try:
        return json.loads(read_text(path, "--baseline", "report"))
    except FileRefused as exc:
        if not exc.missing:   # there, but a pipe, a device, too large...
            raise
        return {}   # absent: an older report without it
    except ValueError:
        return {}


def _change(old, new) -> float | None:
    if old == 0:
        return None if new == 0 else math.inf
    return (new - old) / abs(old)


#: Checked figures renamed since earlier reports (one name per definition): a baseline's old name
#: is compared with the new one.
RENAMED = {**{f"summary.{w}.{a}": f"summary.{w}.{b}" for w in ("primary", "secondary")
              for a, b in (("cg_pd_uV_per_e", "cg_jdep_uV_per_e"), ("cg_out_spice_uV_per_e", "cg_out_0_30_uV_per_e"),
                           ("cg_out_physics_uV_per_e", "cg_out_0_uV_per_e"))},
           **{f"model_vs_spice.{w}.dark_signal_V": f"model_vs_spice.{w}.pedestal_V" for w in ("primary", "secondary")},
           # the camera's sigma_d (EMVA) was checked as "read_noise_e", a name the Noise section's read noise has
           **{f"camera.read_noise_e_{w}": f"camera.sigma_d_e_{w}" for w in ("primary", "secondary")}}
#: Figures earlier reports made that are not about the design (the other pixel families; the frame
#: models' validation, kept for the reference chip): gone from a new report, they are "retired".
RETIRED = ("families.", "frame.dv_kmh", "frame.lowgse_best_ratio")


def _in_percent(name: str, c: dict) -> tuple[str, dict]:
    """A baseline's checked fraction (``*_frac``, unit "1": reports before one unit per figure) as
    today's ``*_pct`` in % (``build.as_percent``)."""
    if c.get("unit") == "1" and name.endswith("_frac"):
        return name[:-5] + "_pct", {**c, "value": 100.0 * c["value"], "unit": "%", "tol_abs": 100.0 * c["tol_abs"]}
    return name, c


def _checked(old: dict, new: dict) -> list[dict]:
    rows = []
    old = dict(_in_percent(RENAMED.get(k, k), v) for k, v in old.items())
    for name in sorted(set(old) | set(new)):
        o, n = old.get(name), new.get(name)
        if o is None:
            rows.append({"figure": name, "old": None, "new": n["value"], "unit": n["unit"], "status": "added"})
            continue
        if n is None:
            rows.append({"figure": name, "old": o["value"], "new": None, "unit": o["unit"],
                         "status": "retired" if name.startswith(RETIRED) else "removed"})
            continue
        tol = max(o["tol_rel"] * abs(o["value"]), o["tol_abs"])
        delta = n["value"] - o["value"]
        status = "moved" if abs(delta) > tol else ("changed" if delta != 0 else "same")
        rows.append({"figure": name, "section": n["section"], "old": o["value"], "new": n["value"],
                     "unit": n["unit"], "delta": delta, "change_frac": _change(o["value"], n["value"]),
                     "tolerance": tol, "status": status})
    return rows


def _is_num(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _tables(old: dict, new: dict) -> list[dict]:
    out = []
    for name in sorted(set(old) | set(new)):
        if name not in old or name not in new:
            out.append({"table": name, "status": "added" if name in new else "removed"})
            continue
        to, tn = old[name], new[name]
        key = to["columns"][0] if to["columns"] else ""
        for i in range(max(len(to["rows"]), len(tn["rows"]))):
            if i >= len(to["rows"]) or i >= len(tn["rows"]):
                out.append({"table": name, "row": i, "status": "row added" if i >= len(to["rows"]) else "row removed"})
                continue
            ro, rn = to["rows"][i], tn["rows"][i]
            for j, col in enumerate(tn["columns"]):
                a = ro[j] if j < len(ro) else None
                b = rn[j] if j < len(rn) else None
                if a == b:
                    continue
                cell = {"table": name, "row": i, "label": str(rn[0]) if rn else "", "column": col, "old": a, "new": b,
                        "key_column": key, "status": "changed"}
                if _is_num(a) and _is_num(b):
                    cell["change_frac"] = _change(a, b)
                out.append(cell)
    return out


def _netlists(old: dict, new: dict) -> list[dict]:
    out = []
    for name in sorted(set(old) | set(new)):
        a, b = old.get(name), new.get(name)
        if a == b:
            continue
        lines = [ln for ln in difflib.unified_diff((a or "").splitlines(), (b or "").splitlines(), lineterm="", n=0)
                 if ln[:1] in "+-" and not ln.startswith(("+++", "---"))]
        out.append({"netlist": name, "status": "added" if a is None else "removed" if b is None else "changed",
                    "lines": lines[:40], "n_lines": len(lines)})
    return out


def _flat(d, prefix=""):
    if isinstance(d, dict):
        out = {}
        for k, v in d.items():
            out.update(_flat(v, f"{prefix}{k}."))
        return out
    return {prefix[:-1]: d}


def _design(old: dict, new: dict) -> list[dict]:
    a, b = _flat(old), _flat(new)
    return [{"field": k, "old": a.get(k), "new": b.get(k)} for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]


def _specs(old: list, new: list) -> list[dict]:
    """Each spec in either revision: worst values, margins and status, ranked by margin used."""
    a, b = {r["spec"]: r for r in old}, {r["spec"]: r for r in new}
    out = []
    for name in list(b) + [n for n in a if n not in b]:
        o, n = a.get(name), b.get(name)
        row = {"spec": name, "limit": (n or o)["limit"], "unit": (n or o)["unit"],
               "old_value": o and o.get("value"), "new_value": n and n.get("value"),
               "old_margin_pct": o and o.get("margin_pct"), "new_margin_pct": n and n.get("margin_pct"),
               "old_status": o["status"] if o else "absent", "new_status": n["status"] if n else "removed",
               "new_worst": n and n.get("worst")}
        if o and n and o["limit"] != n["limit"]:
            row["note"] = f"limit changed from {o['limit']}"
        if row["old_margin_pct"] is not None and row["new_margin_pct"] is not None:
            row["margin_used_pct"] = row["old_margin_pct"] - row["new_margin_pct"]
        row["verdict"] = ("newly failing" if row["new_status"] == "fail" and row["old_status"] != "fail" else
                          "still failing" if row["new_status"] == "fail" else
                          "fixed" if row["old_status"] == "fail" else row["new_status"])
        out.append(row)
    return sorted(out, key=lambda r: (r["verdict"] != "newly failing", -(r.get("margin_used_pct") or 0.0)))


def diff_reports(base: dict, folder: Path) -> dict:
    """Diff the report in ``folder`` against the loaded baseline report ``base``."""
    new = load_report(folder)
    checked = _checked(base["summary"]["checked"], new["summary"]["checked"])
    moved = [r["figure"] for r in checked if r["status"] in ("moved", "removed")]
    pictures = sorted(n for n in set(base["pictures"]) | set(new["pictures"])
                      if base["pictures"].get(n) != new["pictures"].get(n))
    notes = []
    if base["summary"].get("profile") != new["summary"].get("profile"):
        notes.append(f"profiles differ: baseline {base['summary'].get('profile')}, this report "
                     f"{new['summary'].get('profile')} (sweep densities differ, so small moves are expected)")
    specs = _specs(base.get("signoff", []), new["signoff"])
    newly = [r["spec"] for r in specs if r["verdict"] == "newly failing"]
    by_specs = bool(new["signoff"])
    return {"baseline": base["folder"], "baseline_design": base["summary"].get("design"),
            "design_changes": _design(base["design"], new["design"]),
            "checked": checked, "moved": moved, "passed": not newly if by_specs else not moved,
            "by_specs": by_specs, "specs": specs, "newly_failing": newly,
            "tables": _tables(base["tables"], new["tables"]),
            "netlists": _netlists(base["netlists"], new["netlists"]),
            "pictures": pictures, "notes": notes}
