"""Design closure: how ``pixelkit close`` made this revision, read from the path it wrote beside
the design file (``<design stem>.close.json``, docs/close.md): the knobs it moved and their bounds,
every candidate with its smallest margin and objective, each spec's worst margin at the end, the
yield, the circuit choices it compared. Nothing is simulated here; the section says when the design
file is not the one close wrote (its sha256 differs) and is unavailable when close did not write it.
"""
from __future__ import annotations

import json
from pathlib import Path

from . import Figure, Section, Table

TITLE = "Design closure (pixelkit close)"


def path_of(design) -> Path | None:
    """``<stem>.close.json`` beside the design file, when there is one."""
    if not getattr(design, "source", None):
        return None
    p = Path(design.source).with_name(Path(design.source).stem + ".close.json")
    return p if p.is_file() else None


def inputs(ctx) -> dict:
    """What the section reads besides the design (the report's section cache keys on it)."""
    p = path_of(ctx.design)
    if p is None:
        return {"close_json": None}
    from ...readfile import sha256_file
    return {"close_json": sha256_file(p, "close.json", "json")[:16]}


def build(ctx) -> Section:
    from ...errors import PixelkitError
    from ...readfile import read_text
    p = path_of(ctx.design)
    if p is None:
        stem = Path(ctx.design.source).stem if getattr(ctx.design, "source", None) else "<design>"
        return Section.needs_input(TITLE, f"{stem}.close.json beside the design file",
                                   "written by pixelkit close; this revision was not closed by it (docs/close.md)")
    try:
        r = json.loads(read_text(p, "close.json", "json"))
    except (ValueError, PixelkitError) as exc:
        return Section.unavailable(TITLE, f"{p.name} is not a close record ({type(exc).__name__}: {exc})")
    from ...close.output import STATUS, candidates, digest
    text_now = read_text(Path(ctx.design.source), "design", "design")
    same = r.get("out_sha256") == digest(text_now)
    src = Path(r.get("source", "?")).name
    obj = r["objective"]
    text = [f"This revision was written by pixelkit close from {src}: {STATUS.get(r['status'], r['status'])}. "
            f"{candidates(r)} candidates, {r['spice_runs']} SPICE runs ({r['spice_cached']} from the cache), "
            f"{r['wall_s']:.0f} s wall" + (f" ({r['cpu_s']:.0f} s CPU)" if r.get("cpu_s") is not None else "")
            + f"; objective {obj['goal']}: {obj['shown_start']} at the start, {obj['shown']} "
            f"closed. Every candidate was re-verified in SPICE, the accepted ones on the whole sign-off grid "
            "(docs/close.md).",
            "The design file is the one close wrote (sha256 " + r["out_sha256"][:12] + ")." if same else
            "The design file differs from the one close wrote (its sha256 does not match the record): the "
            "tables below describe the revision close wrote, not necessarily this file."]
    y = r.get("yield")
    if y:
        text.append(y["text"])
    if r.get("conflict"):
        text.append("Conflict at the best compromise: " + r["conflict"]["text"])
    tables = [Table("closure_knobs", "Knobs: bounds, start and closed value",
                    ["knob", "min", "max", "scale", "start", "closed", "at bound"],
                    [[k["key"], k.get("min", "-"), k.get("max", "-"), k.get("scale", "choice"), k["start"],
                      k["value"], k.get("at_bound") or "-"] for k in r["knobs"]])]
    if r.get("choices"):
        tables.append(Table("closure_choices", "Circuit choices: each solved on its own",
                            ["choice", "outcome", "smallest margin (%)", obj["goal"], "chosen", "conflict"],
                            [[c["choice"], c["status"], c["smallest_margin_pct"], c["objective_shown"],
                              "yes" if c["chosen"] else "", c["conflict"] or ""] for c in r["choices"]]))
    tables.append(Table("closure_path", "The path: every candidate (the start first), each verified at the "
                        "modelled conditions and, when it held there, on the whole grid",
                        ["iteration", "choice", "mode", "accepted", "verified on", "smallest margin (%)", "objective",
                         "SPICE runs", "from cache", "wall (s)", "knobs"],
                        [[i["iteration"], i.get("choice", ""), i["mode"], "yes" if i["accepted"] else "no",
                          i["verified_on"], i["smallest_margin_pct"], i["objective"], i["spice_runs"],
                          i["spice_cached"], i["wall_s"], "; ".join(f"{k} = {v}" for k, v in i["knobs"].items())]
                         for i in r["iterations"]]))
    tables.append(Table("closure_margins", "Each spec's worst margin at the end (% of its limit) and where",
                        ["spec", "worst margin (%)", "where", "target (%)"],
                        [[n, s["margin_pct"], s["where"] or "-", s["target_pct"]] for n, s in r["final"].items()]))
    fig = ctx.figure("closure_path.png")
    _plot(r, fig)
    return Section(TITLE, text=text, tables=tables,
                   figures=[Figure(fig.name, "The smallest margin over all specs and conditions (left) and the "
                                             "objective (right) of every candidate; filled: accepted")],
                   data={"record": p.name, "same_file": same, "status": r["status"], "passes": r["passes"],
                         "final": r["final"], "yield": y, "conflict": r.get("conflict")})


def _plot(r: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    goal = r["objective"]["goal"]
    scale, unit = _unit(goal.split(" ", 1)[1])
    its = r["iterations"]
    fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.2))
    runs = list(dict.fromkeys(i.get("choice", "") for i in its))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for n, run in enumerate(runs):
        pts = [(k, i) for k, i in enumerate(its) if i.get("choice", "") == run]
        c = colours[n % len(colours)]
        for ax, get in ((a, lambda i: i["smallest_margin_pct"]),
                        (b, lambda i: None if i["objective"] is None else i["objective"] / scale)):
            xs = [k for k, _ in pts]
            ys = [_finite(get(i)) for _, i in pts]
            ax.plot(xs, ys, color=c, lw=0.8, alpha=0.6, label=run or None)
            ax.scatter([k for (k, i), y in zip(pts, ys) if i["accepted"]], [y for (_, i), y in zip(pts, ys)
                                                                             if i["accepted"]], color=c, zorder=3)
            ax.scatter([k for (k, i), y in zip(pts, ys) if not i["accepted"]],
                       [y for (_, i), y in zip(pts, ys) if not i["accepted"]], facecolor="none", edgecolor=c, zorder=3)
    a.set_yscale("symlog", linthresh=1.0)
    a.axhline(0.0, color="k", lw=0.6)
    a.set_ylabel("smallest margin (% of limit)")
    b.set_ylabel(f"{goal}" + (f" ({unit})" if unit else ""))
    b.ticklabel_format(axis="y", useOffset=False)
    for ax in (a, b):
        ax.set_xlabel("candidate (filled: accepted)")
    if len(runs) > 1:
        a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _finite(x):
    return float("nan") if x is None or abs(x) == float("inf") else x


def _unit(what: str) -> tuple[float, str]:
    """(divide SI by, unit) of the objective for the plot."""
    from ...verify.figures import FIGURES, unit_scale
    if what in FIGURES:
        f = FIGURES[what]
        kind, scale = unit_scale(f.unit, f.dim)
        return (scale if kind == "lin" else 0.01 if kind == "%" else 1.0), f.unit
    return (1e-12, "um2") if what == "area" else (1.0, "SI")
