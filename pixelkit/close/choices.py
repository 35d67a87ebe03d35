"""The circuit choices of ``pixelkit close`` (docs/close.md, "Circuit choices"): which combination of
the choice knobs (``"pixel.gate_drive" = { choices = [...] }``) close solves the numeric knobs for.

``[close] choose = "screen"`` (default): every combination's start (its numeric knobs where the file
writes them, else mid-bounds) is simulated where the specs bind, and the combinations are closed in
the order of that screen until one passes:

1. The first combination as listed (the designer's first guess) is verified on the whole grid: the
   ``SCREEN`` worst conditions of each spec there are the screen's conditions (its close starts from
   the same simulations: the cache replays them).
2. Every other combination's start is simulated at those conditions, for the specs measured there.
3. The rows the choice moves (a (spec, condition) whose margin differs between combinations: the AFE
   gain error does not depend on how the pixel's gates are driven) rank them. On each row, each
   combination's shortfall below its target (0 when it meets it) is compared with the best
   combination's there; a combination is as far behind as its worst row: the least behind first
   (0: no other combination does better on any row it fails), then the largest smallest margin,
   then as listed. A row every combination fails alike (the secondary's settling while the OTA
   still slews) does not decide; the row one circuit fails and the other meets does.
4. Close solves the first; a combination that ends passing ends the search; otherwise the next one.

So a later combination with a better objective is not sought once one passes: a choice is a circuit
decision (a rail, a device type), and the screen orders them by how far each starts from passing
where the specs bind. ``choose = "all"`` closes every combination and keeps the passing one with the
best objective (the cost: one close per combination).
"""
from __future__ import annotations

import itertools
import math

from ..errors import ConfigError
from . import margins as mg
from .knobs import Space
from .run import Closer

#: The screen's conditions: each spec's this many worst conditions at the first combination's start.
SCREEN = 2


def choose(design, backend, jobs, scheduler, tell, say) -> dict:
    """One close per combination of the circuit choices, in the screen's order (one close without any);
    the result: the passing revision (the first found, or with ``choose = "all"`` the best objective),
    else the best compromise (the largest smallest margin)."""
    say = say or (lambda _t: None)
    numeric = [k for k in design.close.knobs if not k.choices]
    choice = [k for k in design.close.knobs if k.choices]
    if not choice:
        return Closer(design, backend, jobs, scheduler, tell, say, numeric).run()
    setups = []
    for combo in itertools.product(*(k.choices for k in choice)):
        setting = {k.name: c for k, c in zip(choice, combo)}
        label = " [" + ", ".join(f"{k} = {v}" for k, v in setting.items()) + "]"
        base, active, left_out = _under(design, setting, numeric)
        setups.append({"setting": setting, "label": label, "base": base, "active": active, "left_out": left_out})
    every = design.close.choose == "all" or len(setups) == 1
    screens = None if every else screen(setups, backend, jobs, scheduler, tell, say)
    order = list(range(len(setups))) if screens is None else sorted(
        range(len(setups)), key=lambda i: rank(screens[i], i))
    runs = []
    for i in order:
        s = setups[i]
        say(f"close{s['label']}: solving the numeric knobs with this choice")
        r = Closer(s["base"], backend, jobs, scheduler, tell, say, s["active"], refuse_idle=False,
                   label=s["label"]).run()
        r["setting"], r["left_out"], r["label"] = s["setting"], s["left_out"], s["label"].strip(" []")
        r["screen"] = None if screens is None else screens[i]
        runs.append(r)
        if r["passes"] and not every:
            break
    if len(runs) == len(setups):
        for k in numeric:
            if all(k.name in r["left_out"] or k.name in r["idle"] for r in runs):
                raise ConfigError(design.source, f"close.knobs.{k.name}", k.name, "a knob some spec depends on "
                                  "with one of the choices: it moved no figure of any spec at its binding "
                                  "conditions with any")
    sense = design.close.goal[0]
    passing = [r for r in runs if r["passes"]]
    if passing:
        best = (min if sense == "min" else max)(passing, key=lambda r: r["objective"]["value"])
    else:
        best = max(runs, key=lambda r: -1e300 if r["smallest_margin_pct"] is None else r["smallest_margin_pct"])
    out = dict(best)
    out["overrides"] = {**best["setting"], **best["overrides"], **{k: None for k in best["left_out"]}}
    from .knobs import written
    absent = {k.name for k in numeric if _value(design, k.name) is None or not written(design, k.name)}
    out["knobs"] = ([{"key": k.name, "choices": list(k.choices), "start": str(_value(design, k.name)),
                      "value": best["setting"][k.name]} for k in choice]
                    + [dict(k, start="(absent)") if k["key"] in absent else k for k in best["knobs"]]
                    + [{"key": k, "start": str(_value(design, k)), "value": "(left out)"} for k in best["left_out"]])
    out["iterations"] = [dict(i, choice=r["label"]) for r in runs for i in r["iterations"]]
    out["spice_runs"] = sum(r["spice_runs"] for r in runs) + sum((s or {}).get("spice_runs", 0) for s in
                                                                   (screens or []))
    out["spice_cached"] = sum(r["spice_cached"] for r in runs) + sum((s or {}).get("spice_cached", 0) for s in
                                                                       (screens or []))
    out["wall_s"] = sum(r["wall_s"] for r in runs) + sum((s or {}).get("wall_s", 0.0) for s in (screens or []))
    closed = {r["label"]: r for r in runs}
    out["choices"] = []
    for i in order:
        s, r = setups[i], closed.get(setups[i]["label"].strip(" []"))
        sc = None if screens is None else {k: v for k, v in screens[i].items() if k not in ("short", "behind")}
        if r is None:   # screened, not closed: another passed first
            out["choices"].append({"choice": s["label"].strip(" []"), "status": "screened", "passes": None,
                                   "objective": None, "objective_shown": "-", "smallest_margin_pct": None,
                                   "left_out": s["left_out"], "idle": [], "conflict": None, "chosen": False,
                                   "screen": sc})
            continue
        out["choices"].append({"choice": r["label"], "status": r["status"], "passes": r["passes"],
                               "objective": r["objective"]["value"], "objective_shown": r["objective"]["shown"],
                               "smallest_margin_pct": r["smallest_margin_pct"], "left_out": r["left_out"],
                               "idle": r["idle"], "conflict": (r.get("conflict") or {}).get("text"),
                               "chosen": r is best, "screen": sc})
    out["choose"] = "all" if every else "screen"
    return out


def screen(setups: list, backend, jobs, scheduler, tell, say) -> list[dict]:
    """Each combination's start where the specs bind (the module's steps 1 - 3): per setup
    {"short": its smallest margin less target over the rows the choice moves, "short_pct", "conditions",
    "rows": how many rows moved, "spice_runs", "spice_cached", "wall_s"}."""
    import time
    from .run import _Counter
    t0 = time.perf_counter()
    counter = _Counter()
    closers = [Closer(s["base"], backend, jobs, scheduler, tell, say, s["active"], refuse_idle=False,
                      label=s["label"]) for s in setups]
    first = closers[0]
    with counter.c:
        tell(f"choice screen: the start with{setups[0]['label']} on the whole grid")
        x0, _notes = first.space.start(first.base)
        p0 = first.full(x0)
        pairs = []
        for name in (s.name for s in first.base.spec):
            rows = sorted(((-math.inf if m is None else m, c) for (n, c), m in p0.margins.items() if n == name),
                          key=lambda mc: (mc[0], mc[1]))
            pairs += [(name, c) for _m, c in rows[:SCREEN]]
        pairs = sorted(set(pairs))
        groups = first.groups(pairs)
        conds = sorted(groups)
        margins = [{k: p0.margins.get(k) for k in pairs}]
        for cl in closers[1:]:
            tell(f"choice screen: the start with{cl.label} at {len(conds)} conditions")
            x, _n = cl.space.start(cl.base)
            d = cl.space.design(cl.base, x)
            (figs,) = cl.at([d], conds, groups, "choice screen")
            margins.append({(n, c): mg.margin(cl.spec[n], figs.get(c, {}).get(cl.spec[n].fig.name))
                            for n, c in pairs})
    moved = [k for k in pairs if len({None if m[k] is None else round(m[k], 9) for m in margins}) > 1]

    def shortfall(m, k):   # below target: how far (<= 0); not measured: -inf
        return -math.inf if m[k] is None else min(m[k] - first.target(k), 0.0)
    best = {k: max(shortfall(m, k) for m in margins) for k in moved}
    out = []
    for m in margins:
        short = min(((-math.inf if m[k] is None else m[k] - first.target(k)) for k in moved), default=0.0)
        lag = {k: 0.0 if shortfall(m, k) == best[k] else shortfall(m, k) - best[k] for k in moved}
        behind = min(lag.values(), default=0.0)
        worst = min(moved, key=lambda k: (lag[k], -math.inf if m[k] is None else m[k]), default=None)
        out.append({"behind": behind, "short": short,
                    "behind_pct": 100 * behind if math.isfinite(behind) else None,
                    "short_pct": 100 * short if math.isfinite(short) else None,
                    "worst": None if worst is None else f"{worst[0]} at {worst[1].label}",
                    "conditions": [c.label for c in conds], "rows": len(moved)})
    runs, cached = counter.delta()
    out[0].update(spice_runs=runs, spice_cached=cached, cpu_s=counter.cpu(), wall_s=time.perf_counter() - t0)
    ranked = sorted(range(len(setups)), key=lambda i: rank(out[i], i))
    say("close: circuit choices screened at their start (" + f"{len(moved)} rows the choice moves, "
        f"{len(conds)} conditions): " + "; ".join(
            f"{setups[i]['label'].strip(' []')} short of the best choice by "
            + ("-" if out[i]["behind_pct"] is None else f"{-out[i]['behind_pct']:.3g} %")
            + (f" ({out[i]['worst']})" if out[i]["worst"] else "") + ", smallest margin "
            + ("not measured" if out[i]["short_pct"] is None else f"{out[i]['short_pct']:+.3g} %") for i in ranked))
    return out


def rank(s: dict, i: int) -> tuple:
    """The screen's order: least behind the best choice row by row first, then the largest smallest
    margin, then as listed."""
    return (-s["behind"], -s["short"], i)


def _value(design, key):
    from ..verify.close_table import value_of
    return value_of(design, key)


def _under(design, setting: dict, numeric: list):
    """(the design with the choices of ``setting``, the numeric knobs it has, those it leaves out): a
    knob the design file refuses with this choice (pixel.v_gate with gate_drive = "supply") is left out,
    an absent one starts at the middle of its bounds."""
    from ..sweep.space import design_with
    space = Space(tuple(numeric))
    x0, _notes = space.start(design)
    values = {**setting, **space.overrides(x0)}
    left_out: list = []
    names = {k.name for k in numeric}
    pl = getattr(design, "post_layout", None)
    while True:
        try:
            base = design_with(design, values)
            if pl is not None:   # the post-layout view, as the command asked
                from .knobs import same_view
                base = same_view(design, base)
            break
        except ConfigError as exc:
            if exc.field in names and values.get(exc.field) is not None:
                values[exc.field] = None
                left_out.append(exc.field)
                continue
            key = next(iter(setting))
            raise ConfigError(design.source, f"close.knobs.{key}.choices", setting[key],
                              f"a choice the design can take ({exc.field} = {exc.value!r}: expected {exc.allowed})"
                              ) from None
    return base, [k for k in numeric if k.name not in left_out], left_out
