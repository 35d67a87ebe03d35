"""The report's verdict: what its banner says, what ``summary.json`` keeps under ``verdict`` and
the exit status of ``pixelkit report`` (``errors.verdict_exit``, the rule ``verify`` follows).

PASS: every spec of the design's ``[spec]`` table was measured at every condition asked and
holds there, and every section built. FAIL: a spec fails (at its worst condition, or on its
Monte Carlo yield), or the revision diff finds a spec newly failing / a checked figure moved.
NOT MEASURED: nothing failed, but a spec was not run or not measured at some of its
conditions (the quick profile runs the nominal condition only), or a section failed to build.
SIMULATION FAILED: nothing failed, but a simulation of the sign-off did (exit 4).
A design without specs has no verdict ("NO SPECS"): the report still exits on its sections.
"""
from __future__ import annotations

from ..errors import verdict_exit

#: The profiles as the banner and the command line name them.
PROFILES = {"quick": "nominal only", "full": "full grid"}


def _failing(row: dict) -> dict:
    """A failing spec as the banner shows it: its worst condition, value and limit."""
    return {"spec": row["spec"], "worst": row.get("worst"), "value": row.get("value"), "unit": row.get("unit", ""),
            "limit": row.get("limit", ""), "margin": row.get("margin"),
            "failing_at": len(row.get("failing_at", [])), "conditions": row.get("conditions"),
            "yield": bool(row.get("failing_at")) and str(row["failing_at"][0]).startswith("yield")}


def verdict(summary: dict, signoff: dict | None, diff: dict | None = None) -> dict:
    """The verdict of a report from its ``summary`` (sections' statuses, profile), the sign-off
    section's data (None when the design has no specs or the section did not build) and the diff."""
    rows = (signoff or {}).get("rows") or []
    failed_sections = [k for k, v in summary["sections"].items() if v == "failed"]
    failing = [_failing(r) for r in rows if r["status"] == "fail"]
    unmeasured = [{"spec": r["spec"], "status": r["status"],
                   "where": r.get("not_measured_at") or [r.get("why", "")]} for r in rows
                  if r["status"] in ("not measured", "not run")]
    diff_failed = bool(diff) and not diff.get("passed", True)
    statuses = ([r["status"] for r in rows] + ["fail"] * diff_failed + ["not measured"] * len(failed_sections))
    # the team's rule (errors.verdict_exit, as verify.signoff.exit_status): 1 > 4 > 5 > 0; a design
    # without specs has nothing to judge but its diff and sections
    code = verdict_exit(statuses, simulation_failed=bool((signoff or {}).get("errors"))) if statuses else 0
    word = {1: "FAIL", 4: "SIMULATION FAILED", 5: "NOT MEASURED", 0: "PASS"}[code]
    if not rows and code == 0:
        word = "NO SPECS"
    return {"verdict": word, "exit": code, "specs": len(rows),
            "passing": sum(r["status"] == "pass" for r in rows),
            "view": (signoff or {}).get("view", "schematic"),
            "profile": PROFILES.get(summary.get("profile"), summary.get("profile")),
            "conditions": ((signoff or {}).get("grid") or {}).get("conditions"),
            "failing": failing, "not_measured": unmeasured, "failed_sections": failed_sections,
            "diff_failed": diff_failed}


def line(v: dict) -> str:
    """The verdict in one line (the terminal's first line after the report's path)."""
    head = (f"{v['verdict']}: {v['passing']} of {v['specs']} specs pass ({v['view']}, {v['profile']}"
            + (f", {v['conditions']} condition{'s' if v['conditions'] != 1 else ''}" if v.get("conditions") else "") + ")")
    if not v["specs"]:
        head = f"{v['verdict']}: the design has no [spec] table ({v['view']}, {v['profile']})"
    parts = [head]
    for x in v["failing"]:
        parts.append(f"FAIL {x['spec']}: {_num(x['value'])} {x['unit']} at {x['worst']} (limit {x['limit']}"
                     + (f"; fails at {x['failing_at']} of {x['conditions']} conditions" if x["failing_at"] > 1 else "")
                     + ")")
    for x in v["not_measured"]:
        parts.append(f"{x['status'].upper()} {x['spec']}: " + "; ".join(str(w) for w in x["where"] if w))
    for k in v["failed_sections"]:
        parts.append(f"section {k} failed to build")
    if v["diff_failed"]:
        parts.append("the revision diff fails (below)")
    return "\n  ".join(parts)


def _num(x) -> str:
    return "-" if x is None else (f"{x:.4g}" if isinstance(x, float) else str(x))
