"""Sign-off section, first in the report: every spec of the design's ``[spec]`` table, its worst
condition over the ``[verify]`` grid, margin, pass / fail and Monte Carlo yield (``pixelkit.verify``).

The full profile runs the design's own grid and Monte Carlo (what ``pixelkit verify`` runs,
through the same simulation cache, so a report after a verify simulates nothing); the quick
profile runs the nominal condition only, without Monte Carlo, and says so.
"""
from __future__ import annotations

from . import Checked, Section, Table

TITLE = "Sign-off: specs over corners, Monte Carlo yield, power"


def _verify(ctx) -> dict:
    from ...verify import conditions
    from ...verify.run import verify
    d = ctx.design
    if ctx.quick:
        n = conditions.nominal(d)
        return verify(d, corners=(n.corner,), temperatures=(n.temperature,), supplies=(0.0,), mc=0,
                      backend=ctx.backend, jobs=ctx.jobs, status=ctx.status("sign-off"))
    return verify(d, backend=ctx.backend, jobs=ctx.jobs, mc_full=ctx.exhaustive, status=ctx.status("sign-off"))


def prefetch(ctx) -> None:
    """The verify run starts in the background when the report starts; the other sections are
    built beside it (report.build)."""
    if ctx.design.spec:
        ctx.start("signoff.verify", lambda: _verify(ctx))


def build(ctx) -> Section:
    from ...verify.signoff import COLUMNS, csv_rows, mc_count, where
    d = ctx.design
    if not d.spec:
        return Section.unavailable(TITLE, "the design has no [spec] table (docs/verify.md)")
    ctx.progress("sign-off")
    r = ctx.shared("signoff.verify", lambda: _verify(ctx))
    g, mc = r["grid"], r["mc"]
    text = [f"Every spec of the design file at {g['conditions']} condition(s): process corners "
            f"{', '.join(g['corners'])}, {', '.join(f'{t:g}' for t in g['temperatures_C'])} degC, supply "
            f"{', '.join(f'{100 * s:+g} %' for s in g['supplies'])} of {r['supply_V']:g} V"
            + (" (quick profile: the nominal condition only; the full report and 'pixelkit verify' run the "
               "design's grid)" if ctx.quick else "") + ". A spec passes when it holds at every condition (the worst "
            "case, as a CACE datasheet decides); the margin is the distance to the nearer limit at the worst "
            "condition.",
            (f"Monte Carlo: {mc_count(mc)} at {mc['condition']}, seed {mc['seed']}, drawn from "
             f"{mc['draws']}; yield with its {100 * mc['confidence']:g} % Clopper-Pearson interval and the margin "
             "of the mean in sample sigmas." if mc["samples"] else "No Monte Carlo in this profile.")]
    fails = [f"{x['spec']} {where(x)}" for x in r["rows"] if x["status"] == "fail"]
    text.append(("FAIL: " + "; ".join(fails)) if fails else "Every spec passes at every condition.")
    text += [f"Simulation failed at {e['condition']} ({e['group']}): {e['error']}" for e in r["errors"][:5]]
    tables = [Table("signoff", "Sign-off table", list(COLUMNS), csv_rows(r["rows"]))]
    power = r.get("power")   # verify's power measurement: at the nominal condition
    if power and "per_column_W" not in power:   # a pixel read by role (rolepix.power): one column, the chip
        tables.append(Table("signoff_power", "Power at the nominal condition (W): one column's read and idle "
                            f"supply current over the frame (duty {power['duty']:.3g}), the array; the estimate is "
                            "the load's bias x supply x (1 + duty)", ["block", "SPICE", "estimate"],
                            [["column", power["column_W"], power["estimate_W"] / (power["chip_W"] / power["column_W"])],
                             ["chip", power["chip_W"], power["estimate_W"]]]))
    elif power:
        pc = power["per_column_W"]
        tables.append(Table("signoff_power", f"Power per block at the nominal condition ({power['condition']}, W): "
                            "per column of each array and the chip, over a "
                            f"{power['frame_period_s'] * 1e3:.4g} ms frame; the estimate is bias currents x supply "
                            "x duty", ["block", "primary column", "secondary column", "chip", "chip, estimate"],
                            [[b, pc["primary"][b], pc["secondary"][b], power["chip_blocks_W"][b],
                              power["estimate"]["chip_blocks_W"][b]] for b in power["chip_blocks_W"]]))
    checked = [Checked(f"signoff.{x['spec']}", x["value"], x["unit"], tol_rel=0.01,
                       note=f"worst at {x.get('worst')}; limit {x['limit']}") for x in r["rows"] if x.get("value") is not None]
    waves, why = _waves(ctx, r["rows"])
    if waves or why:
        text.append("Waveforms: each failing spec" + (" and each spec asked with --waves" if ctx.waves else "")
                    + " at its worst condition against nominal, the measurement's own readings marked (sample "
                    "instants, levels read), the decks' raw files linked (pixelkit waves FILE.raw opens them)."
                    + "".join(f" {w}" for w in why))
    data = {"waves": waves, "rows": r["rows"], "grid": g, "mc": mc, "errors": r["errors"], "conditions": r["conditions"],
            "mc_values": r["mc_values"], "view": r["view"], "profile": "quick" if ctx.quick else "full",
            "power": None if not power else {k: power.get(k) for k in ("condition", "chip_W", "pixel_W", "column_W")}}
    return Section(TITLE, text=text, tables=tables, checked=checked, data=data,
                   files=[f for w in waves.values() for f in w["files"]])


def _waves(ctx, rows) -> tuple[dict, list]:
    """({spec: its waveform view}, [why a spec asked for has none]) for every failing spec and every
    spec of ``ctx.waves``."""
    from ...verify.waves import spec_waves
    want = [x for x in rows if x["status"] == "fail" or x["spec"] in ctx.waves]
    out, why = {}, []
    for x in want:
        ctx.progress(f"sign-off: waveform of {x['spec']}")
        w = spec_waves(ctx.design, x, ctx.figure("waves/x").parent, "waves", backend=ctx.backend)
        if w is None:
            why.append(f"{x['spec']} has no waveform view ({x['figure']}: its measurement has no transient of "
                       "its own, or it was not measured).")
        else:
            out[x["spec"]] = w
    return out, why
