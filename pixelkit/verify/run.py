"""``verify``: every spec at every condition of the grid, the Monte Carlo yield, the table.

Work is cut into tasks (one condition or one Monte Carlo sample x one measurement group)
that run through ``spice.executors.run_tasks``: local worker threads by default (each
drives one ngspice at a time), a Dask cluster with ``scheduler``. Every deck goes through
the engine's content-hash cache as soon as it finishes, so an interrupted run resumes
where it stopped and a re-run with nothing changed simulates nothing. A task whose
simulation fails is kept with ngspice's message; the specs it feeds are reported
"not measured" at that condition, never dropped.
"""
from __future__ import annotations

import math
import time

from ..errors import ConfigError, PixelkitError, SimulationError
from . import conditions, measure, mismatch
from .figures import FIGURES
from .signoff import _margin
from .yields import decided, looks, stop_confidence


class _Dual:
    """The dual pixel's suite: ``verify.measure``'s groups and figures, ``conditions.at``."""
    FIGURES = FIGURES
    GROUPS = measure.GROUPS
    run_group = staticmethod(measure.run_group)
    groups_for = staticmethod(measure.groups_for)
    figures = staticmethod(measure.figures)
    at = staticmethod(conditions.at)


def suite(design):
    """What verify runs for ``design``: its family's suite (a design read by role hands over
    ``rolepix.suite``), else the dual pixel's."""
    return getattr(design, "suite", None) or _Dual


def _task(task):
    """The groups of one condition (and draw), in one worker: groups that share decks (the
    pixel, lag and gse groups start from the same dark / small / saturated decks) find them
    in the cache instead of simulating them twice at once. A group whose simulation fails is
    kept with ngspice's message; the others still run. A sixth item, the figure names the task is
    run for, lets a group leave out the decks of figures nobody asked (``measure.asking``)."""
    design, cond, groups, draw, backend = task[:5]
    su = suite(design)
    d = su.at(design, cond)
    out = {}
    with measure.asking(task[5] if len(task) > 5 else None):
        for group in groups:
            try:
                out[group] = {"ok": True, "raw": su.run_group(group, d, draw, backend)}
            except SimulationError as exc:
                out[group] = {"ok": False, "error": f"{exc.what or exc.deck}: {exc.message}"}
    return out


def measure_at(items, backend: str = "batch", jobs=None, scheduler=None, desc: str = "measuring") -> list[dict]:
    """The figures of each ``(design, condition, groups)`` item, as ``verify`` measures them (same
    tasks, same decks, the same cache): per item ``{"figures": {name: SI value or None},
    "errors": [message, ...]}``. For callers that need some groups at some conditions of several
    designs (``pixelkit close``: its sensitivities and candidates) rather than a whole grid."""
    from ..spice.executors import run_tasks
    tasks = [(d, c, tuple(gs), None, backend) for d, c, gs in items]
    outs = [None] * len(tasks)
    for i, out in run_tasks(_task, tasks, jobs=jobs, scheduler=scheduler, desc=desc):
        outs[i] = out
    result = []
    for (d, c, _gs, _draw, _b), outcome in zip(tasks, outs):
        raw = {g: o["raw"] for g, o in outcome.items() if o["ok"]}
        result.append({"figures": _finite(suite(d).figures(raw)),
                       "errors": [f"{c.label} ({g}): {o['error']}" for g, o in outcome.items() if not o["ok"]]})
    return result


def post_layout_view(design):
    """The design whose decks carry the parasitics extracted from its own layout
    (``layout.pex.overlay``: every generator adds them; a technology without a process stack
    is refused naming it); every measurement then runs on that view unchanged."""
    from ..layout.pex.overlay import post_layout_view as view
    return view(design)


def plan(design, grid: list, mc: int) -> tuple[list, list]:
    """([(condition, its groups, the figures asked there)], Monte Carlo specs): which groups run where. The
    Monte Carlo runs at the nominal condition, so it serves the specs that hold there and whose figure
    mismatch moves."""
    su = suite(design)
    need: dict = {}
    asked: dict = {}
    for s in design.spec:
        for c in conditions.spec_conditions(s, grid):
            asked.setdefault(c, set()).add(s.fig.name)
            for g in su.groups_for([s.fig.name]):
                need.setdefault(c, set()).add(g)
    nominal = [conditions.nominal(design)]
    mc_specs = [s for s in design.spec if mc and s.mc and s.fig.mc and conditions.spec_conditions(s, nominal)]
    order = list(su.GROUPS)
    return [(c, tuple(sorted(gs, key=order.index)), tuple(sorted(asked[c]))) for c, gs in sorted(need.items())], \
        mc_specs


class _Sequential:
    """The Monte Carlo's stages: samples ``[0, n)`` in stages ending at ``yields.looks(mc)`` (one stage
    of ``mc`` with ``full``); after each, the stage's yields decide whether the next one runs
    (``yields.decided``: every Monte Carlo spec's interval wholly at or above min_yield or wholly
    below it at the stopping level). The draws of sample i depend on (seed, i) only, so a run that
    stops at n holds the first n samples of the full run."""

    def __init__(self, design, mc_specs, mc: int, full: bool, task_of):
        self.design, self.specs, self.mc, self.full, self.task_of = design, mc_specs, mc, full, task_of
        self.stops = ([mc] if full else looks(mc)) if mc_specs else []
        self.stage, self.n, self.waiting, self.looked = 0, 0, 0, 0
        self.raw: dict = {}
        self.why = "full count" if full else None

    def first(self) -> list:
        return self._next()

    def _next(self) -> list:
        if self.stage >= len(self.stops):
            return []
        start, self.n = self.n, self.stops[self.stage]
        self.stage += 1
        self.waiting = self.n - start
        return [self.task_of(i) for i in range(start, self.n)]

    def done(self, sample: int, outcome: dict) -> None:
        self.raw[sample] = outcome
        self.waiting -= 1

    def more(self) -> list:
        """The next stage when the current one is complete and has not decided every yield."""
        if self.waiting or self.looked == self.stage:
            return []
        self.looked = self.stage
        if self.full:
            return []
        v = self.design.verify
        samples = [_finite(suite(self.design).figures(_ok(self.raw[i]))) for i in range(self.n)]
        verdicts = []
        for s in self.specs:
            vals = [x for x in (y.get(s.fig.name) for y in samples) if x is not None]
            verdicts.append(decided(sum(_margin(x, s.lo, s.hi) >= 0 for x in vals), len(vals), v.min_yield,
                                    v.confidence, self.mc))
        level = (f"{100 * stop_confidence(v.confidence, self.mc):.4g} % intervals: {100 * v.confidence:g} % "
                 f"shared over {len(self.stops)} looks")
        if all(verdicts):
            self.why = (f"sequential stop: every yield decided against min_yield {100 * v.min_yield:g} % ({level})"
                        if v.min_yield else "sequential stop: min_yield 0 %, the yields decide nothing (set [verify] "
                        "min_yield to have them decide)")
            return []
        if self.stage == len(self.stops):
            self.why = (f"sequential: not every yield decided against min_yield {100 * v.min_yield:g} % before the "
                        f"full count ({level})")
        return self._next()


def _label(task) -> str:
    """What a task simulates, for the progress line."""
    _d, c, groups, draw, _b = task[:5]
    return f"Monte Carlo sample {draw.sample + 1}" if draw is not None else f"{c.label} {'+'.join(groups)}"


def _ok(outcome: dict) -> dict:
    return {g: o["raw"] for g, o in outcome.items() if o["ok"]}


def verify(design, corners=None, temperatures=None, supplies=None, mc: int | None = None, seed: int | None = None,
           backend: str = "batch", jobs=None, scheduler=None, post_layout: bool = False,
           mc_full: bool = False, status=None) -> dict:
    """The sign-off of ``design`` over its grid (or the one given) with its Monte Carlo yield.
    The Monte Carlo stops early once every yield is decided against ``[verify] min_yield``
    (``_Sequential``; with min_yield 0, nothing to decide, after its first stage); ``mc_full``
    runs every one of the ``mc`` samples. ``status(done, total, what)``: told the progress after
    every task (``spice.executors.run_tasks``)."""
    from ..spice.executors import run_tasks
    from .signoff import table
    if post_layout:
        design = post_layout_view(design)
    if not design.spec:
        raise ConfigError(design.source, "spec", None, "a [spec] table with at least one spec (docs/verify.md)")
    t0 = time.perf_counter()
    grid = conditions.grid(design, corners, temperatures, supplies)
    su = suite(design)
    for c in grid:   # a supply corner that puts a reference above the supply: refused before any run
        su.at(design, c)
    mc = design.verify.mc if mc is None else mc
    seed = design.verify.seed if seed is None else seed
    cond_tasks, mc_specs = plan(design, grid, mc)
    src, mc_groups, nominal = None, [], conditions.nominal(design)
    if mc_specs:
        src = mismatch.source(design)
        mc_groups = sorted(su.groups_for([s.fig.name for s in mc_specs]), key=list(su.GROUPS).index)
    seq = _Sequential(design, mc_specs, mc, mc_full,
                      lambda i: (design, nominal, tuple(mc_groups), mismatch.Draw(seed, i, src), backend,
                                 tuple(sorted({s.fig.name for s in mc_specs}))))
    tasks = [*seq.first(), *((design, c, gs, None, backend, names) for c, gs, names in cond_tasks)]
    raw_cond: dict = {}
    errors = []

    def take(task, outcome):
        _d, c, _gs, draw, _b = task[:5]
        if draw is not None:
            seq.done(draw.sample, outcome)
        where = raw_cond.setdefault(c, {}) if draw is None else {}
        for g, out in outcome.items():
            if out["ok"]:
                where[g] = out["raw"]
            else:
                errors.append({"condition": c.label, "group": g, "sample": None if draw is None else draw.sample,
                               "error": out["error"]})

    def more():
        new = seq.more()
        tasks.extend(new)
        return new

    for i, out in run_tasks(_task, tasks, jobs=jobs, scheduler=scheduler, desc="verify", more=more, label=_label,
                            status=status):
        take(tasks[i], out)
    raw_mc = {i: _ok(o) for i, o in seq.raw.items()}
    values = {c: _finite(su.figures(r)) for c, r in raw_cond.items()}
    samples = [_finite(su.figures(raw_mc[i])) for i in sorted(raw_mc)]
    rows = table(design, grid, values, samples, mc_specs)
    _refuse_zero_spread(rows, len(samples))
    return {"design": design.name, "revision": design.revision, "family": getattr(design, "family", "dual_pixel"),
            "rows": rows,
            "grid": {"corners": sorted({c.corner for c in grid}),
                     "temperatures_C": sorted({round(c.temperature - 273.15, 6) for c in grid}),
                     "supplies": sorted({c.supply for c in grid}), "conditions": len(grid)},
            "mc": {"samples": len(samples) if mc_specs else 0, "planned": mc if mc_specs else 0,
                   "stop": seq.why, "seed": seed, "source": src,
                   "draws": mismatch.describe(src) if src else None, "condition": nominal.label,
                   "confidence": design.verify.confidence},
            "supply_V": design.tech.supply,
            "view": "schematic" if getattr(design, "post_layout", None) is None else "post-layout",
            "conditions": [{**c.as_dict(), "label": c.label, "figures": {k: v for k, v in values.get(c, {}).items()
                                                                          if k in {s.fig.name for s in design.spec}}}
                           for c in grid],
            "mc_values": {s.name: [x.get(s.fig.name) for x in samples] for s in mc_specs},
            "raw": _clean({c.label: raw_cond.get(c, {}) for c in grid}),
            "power": _power(grid, raw_cond, nominal),
            "errors": errors, "tasks": len(tasks), "wall_s": time.perf_counter() - t0,
            "failed": [r["spec"] for r in rows if r["status"] == "fail"],
            "unmeasured": [r["spec"] for r in rows if r["status"] not in ("pass", "fail")]}


def _power(grid, raw_cond: dict, nominal) -> dict | None:
    """The power measurement at the nominal condition (else the first of the grid that has one)."""
    for c in [nominal, *grid]:
        p = raw_cond.get(c, {}).get("power")
        if p:
            return {"condition": c.label, **_clean(p)}
    return None


def _finite(figs: dict) -> dict:
    """A figure that came out infinite or NaN (a storage signal of zero makes GSE infinite) is
    not a measurement: None, reported as "not measured" at that condition."""
    return {k: (v if isinstance(v, float) and math.isfinite(v) else None) for k, v in figs.items()}


def _clean(x):
    """Raw measurements with every non-finite number as None (JSON has no Infinity)."""
    if isinstance(x, dict):
        return {k: _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    return None if isinstance(x, float) and not math.isfinite(x) else x


def _refuse_zero_spread(rows, n: int) -> None:
    flat = [r["spec"] for r in rows if r.get("yield") is not None and r["yield"].get("zero_spread")]
    if flat:
        raise PixelkitError(
            f"Monte Carlo of {n} samples: zero spread of {', '.join(flat)}: every sample gave the same value, so "
            "the devices carried no mismatch; a zero-spread Monte Carlo is never a pass (check the model "
            "library's statistics or the technology's [mismatch] table)")

