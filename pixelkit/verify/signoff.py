"""The sign-off table: per spec, the worst condition, its value and margin, pass / fail, yield.

A spec passes when its figure is within its limits at every condition of its grid (the
worst case, as a CACE datasheet decides), and, with ``[verify] min_yield``, when the upper
end of its yield interval is not below it. The margin is the distance to the nearer limit
at the worst condition (negative: outside), in the spec's unit and in % of the limit.
"""
from __future__ import annotations

import math

import numpy as np

from .conditions import spec_conditions
from .figures import shown
from .yields import clopper_pearson, margin_sigma


def _margin(x: float, lo, hi) -> float:
    return min((x - lo) if lo is not None else math.inf, (hi - x) if hi is not None else math.inf)


def limit_text(spec) -> str:
    u, dim = spec.shown_unit, spec.fig.dim
    parts = []
    if spec.lo is not None:
        parts.append(f">= {_fmt(shown(spec.lo, u, dim))}")
    if spec.hi is not None:
        parts.append(f"<= {_fmt(shown(spec.hi, u, dim))}")
    return " and ".join(parts) + (f" {u}" if u else "")


def _fmt(x) -> str:
    return "-" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:.4g}"


def table(design, grid, values: dict, samples: list, mc_specs: list) -> list[dict]:
    conf, min_yield = design.verify.confidence, design.verify.min_yield
    rows = []
    for s in design.spec:
        f, u = s.fig, s.shown_unit
        conds = spec_conditions(s, grid)
        got = [(c, values.get(c, {}).get(f.name)) for c in conds]
        measured = [(c, v) for c, v in got if v is not None and math.isfinite(v)]
        row = {"spec": s.name, "figure": f.name, "unit": u, "limit": limit_text(s),
               "min": None if s.lo is None else shown(s.lo, u, f.dim),
               "max": None if s.hi is None else shown(s.hi, u, f.dim),
               "typ": None if s.typical is None else shown(s.typical, u, f.dim), "note": s.note,
               "conditions": len(conds), "measured": len(measured), "yield": None}
        if not conds:
            row.update(status="not run", why="none of its conditions is in the grid that ran")
            rows.append(row)
            continue
        if len(measured) < len(conds):
            row["not_measured_at"] = [c.label for c, v in got if v is None or not math.isfinite(v)]
        if measured:
            worst_c, worst_v = min(measured, key=lambda cv: _margin(cv[1], s.lo, s.hi))
            m = _margin(worst_v, s.lo, s.hi)
            limit = s.lo if s.hi is None or (s.lo is not None and worst_v - s.lo < s.hi - worst_v) else s.hi
            fails = [c.label for c, v in measured if _margin(v, s.lo, s.hi) < 0]
            row.update(worst=worst_c.label, worst_condition=worst_c.as_dict(), value=shown(worst_v, u, f.dim),
                       value_si=worst_v, margin=_shown_margin(m, worst_v, s, u),
                       margin_pct=100 * m / abs(limit) if limit else None, margin_si=m, failing_at=fails,
                       nominal=next((shown(v, u, f.dim) for c, v in measured if c.supply == 0 and
                                     c.corner == design.corner_name and abs(c.temperature - design.temperature) < 1e-6),
                                    None))
            status = "fail" if fails else ("not measured" if len(measured) < len(conds) else "pass")
        else:
            status = "not measured"
        if s in mc_specs and samples:
            vals = np.array([x.get(f.name, np.nan) for x in samples], float)
            vals = vals[np.isfinite(vals)]
            k = int(sum(_margin(v, s.lo, s.hi) >= 0 for v in vals))
            lo, hi = clopper_pearson(k, len(vals), conf) if len(vals) else (0.0, 1.0)
            spread = float(vals.std(ddof=1)) if len(vals) > 1 else 0.0
            row["yield"] = {"passed": k, "samples": int(len(vals)), "yield": k / len(vals) if len(vals) else None,
                            "interval": [lo, hi], "confidence": conf,
                            "margin_sigma": margin_sigma(vals, s.lo, s.hi) if len(vals) > 1 else None,
                            "mean": shown(float(vals.mean()), u, f.dim) if len(vals) else None,
                            "sigma_si": spread, "zero_spread": len(vals) > 1 and spread == 0.0}
            if min_yield and hi < min_yield and status == "pass":
                status = "fail"
                row["failing_at"] = [f"yield {100 * k / len(vals):.3g} % (interval up to {100 * hi:.3g} %) "
                                     f"below min_yield {100 * min_yield:g} %"]
        row["status"] = status
        rows.append(row)
    return rows


def _shown_margin(m: float, value: float, spec, unit: str) -> float:
    """The margin in the spec's unit (for dB / %: the difference of the shown values)."""
    f = spec.fig
    limit = spec.lo if spec.lo is not None and (spec.hi is None or abs(value - spec.lo) <= abs(spec.hi - value)) else spec.hi
    a, b = shown(value, unit, f.dim), shown(limit, unit, f.dim)
    return a - b if limit == spec.lo else b - a


COLUMNS = ("spec", "limit", "worst condition", "value", "margin", "margin %", "status", "yield %",
           "yield interval %", "yield samples", "margin sigma", "typ", "note")


def csv_rows(rows) -> list[list]:
    out = []
    for r in rows:
        y = r.get("yield") or {}
        out.append([r["spec"], r["limit"], r.get("worst", "-"), r.get("value"), r.get("margin"), r.get("margin_pct"),
                    r["status"], None if not y else 100 * y["yield"],
                    None if not y else f"{100 * y['interval'][0]:.3g} - {100 * y['interval'][1]:.3g}",
                    None if not y else y["samples"], None if not y else y["margin_sigma"], r.get("typ"), r.get("note", "")])
    return out


def exit_status(result: dict) -> int:
    """The exit status of a sign-off result (``verify.run.verify``'s, or any dict with its
    ``rows`` and ``errors``): :func:`pixelkit.errors.verdict_exit` over the rows' statuses - 1 a spec
    fails, 4 a simulation failed, 5 a spec was not run or not measured somewhere, 0 every spec
    measured everywhere and passing. ``verify``, ``report`` and ``close`` call this one rule."""
    from ..errors import verdict_exit
    return verdict_exit([r["status"] for r in result["rows"]], simulation_failed=bool(result.get("errors")))


def not_measured(result: dict) -> list[str]:
    """Each spec that was not measured everywhere, with where (one line each, for stderr)."""
    return [f"{r['spec']}: " + (", ".join(r.get("not_measured_at", [])) or r.get("why", "not measured"))
            for r in result["rows"] if r["status"] not in ("pass", "fail")]


def mc_count(mc: dict) -> str:
    """How many Monte Carlo samples ran, of how many, and why it stopped there."""
    planned = mc.get("planned", mc["samples"])
    if planned == mc["samples"] and (mc.get("stop") or "full count") == "full count":
        return f"{mc['samples']} samples"
    return f"{mc['samples']} of {planned} samples ({mc.get('stop')}; --mc-full runs all {planned})"


def where(row) -> str:
    """Where a spec fails, short: every condition up to four, else a count and the worst."""
    at = row.get("failing_at", [])
    if len(at) <= 4:
        return "at " + ", ".join(at)
    return f"at {len(at)} of {row['conditions']} conditions, worst {row.get('worst')} ({_fmt(row.get('value'))} {row['unit']})"


def text(result: dict) -> str:
    """The table as a terminal shows it."""
    rows = result["rows"]
    head = ["spec", "limit", "worst condition", "value", "margin", "status", "yield [interval] of n", "sigma"]
    body = []
    for r in rows:
        y = r.get("yield")
        ytxt = "-" if not y else (f"{100 * y['yield']:.1f} % [{100 * y['interval'][0]:.1f}, "
                                  f"{100 * y['interval'][1]:.1f}] of {y['samples']}")
        sig = "-" if not y or y["margin_sigma"] is None else f"{y['margin_sigma']:.2f}"
        mtxt = "-" if r.get("margin") is None else f"{_fmt(r['margin'])} ({_fmt(r.get('margin_pct'))} %)"
        body.append([r["spec"], r["limit"], r.get("worst", "-"), f"{_fmt(r.get('value'))} {r['unit']}".strip(),
                     mtxt, r["status"].upper(), ytxt, sig])
    widths = [max(len(str(x)) for x in col) for col in zip(head, *body)]
    lines = ["  ".join(str(x).ljust(w) for x, w in zip(row, widths)).rstrip() for row in [head, *body]]
    g, mc = result["grid"], result["mc"]
    lines.insert(0, f"sign-off of {result['design']} rev {result['revision']} ({result.get('view', 'schematic')}): "
                    f"{g['conditions']} conditions "
                    f"(corners {', '.join(g['corners'])} x {', '.join(f'{t:g}' for t in g['temperatures_C'])} degC x "
                    f"supply {', '.join(f'{100 * s:+g}%' for s in g['supplies'])} of {result['supply_V']:g} V)"
                    + (f"; Monte Carlo {mc_count(mc)} at {mc['condition']}, seed {mc['seed']}, draws: "
                       f"{mc['draws']}" if mc["samples"] else "; no Monte Carlo"))
    for r in rows:
        if r["status"] == "fail":
            lines.append(f"FAIL {r['spec']}: {where(r)}")
        elif r["status"] in ("not measured", "not run"):
            lines.append(f"{r['status'].upper()} {r['spec']}: " + (", ".join(r.get("not_measured_at", []))
                                                                  or r.get("why", "")))
    p = result.get("power")
    if p and "chip_blocks_W" not in p:   # a pixel read by role (rolepix.power)
        lines.append(f"power at {p['condition']}: chip {1e3 * p['chip_W']:.4g} mW (estimate {1e3 * p['estimate_W']:.4g} "
                     f"mW), per column {1e6 * p['column_W']:.4g} uW, read duty {100 * p['duty']:.3g} %")
    elif p:
        blocks, est = p["chip_blocks_W"], p["estimate"]["chip_blocks_W"]
        lines.append(f"power at {p['condition']}, frame {1e3 * p['frame_period_s']:.4g} ms: chip "
                     f"{1e3 * p['chip_W']:.4g} mW (estimate {1e3 * p['estimate']['chip_W']:.4g} mW): "
                     + ", ".join(f"{b} {1e6 * blocks[b]:.4g} uW ({1e6 * est[b]:.4g})" for b in blocks)
                     + f"; per {'pixel' if result.get('family') == 'ratio' else 'dual pixel'} {1e9 * p['pixel_W']:.4g} nW, per column {1e6 * p['column_W']:.4g} uW")
    for e in result.get("errors", [])[:10]:
        lines.append(f"simulation failed at {e['condition']} ({e['group']}): {e['error']}")
    return "\n".join(lines)
