"""The global stage of ``pixelkit close``: before the trust region, a Latin hypercube over the knobs
of the design sections a cheap bench reads alone (docs/close.md, "The global stage").

Why: the local method (``close.run``) steps on linear models of the margins. Where a figure is
not smooth in the knobs it cannot cross: near the reference's AFE values the transistor OTA slews
between the switched-capacitor phases, and a few % in Cc or the bias moves the gain error by a
factor 2 - 7 (docs/close.md). But the specs such a bench measures depend only on that bench's
section: the AFE bench (``verify.measure.afe``) reads ``[afe]`` alone (and the technology, at the
condition), so the AFE gain error is a function of the ``afe.*`` knobs only, whatever the pixel.
That sub-problem is small (the AFE knobs) and cheap (0.6 s per condition against 7 s for a
settling frame), so it is sampled globally instead of stepped into:

1. The block: the numeric knobs in the sections a bench group (``BENCHES``) reads alone; its
   specs: those measured by such groups only. The stage runs when the start fails its grid.
2. Stage A: ``[close] global_samples`` points of a Latin hypercube over the block (in close's coordinates: a log
   knob in its logarithm), the other knobs at the start, plus the start itself, each simulated on
   the bench at the ``SCREEN`` worst conditions of each block spec at the start and the nominal one.
3. Stage B: the ``KEEP`` best of stage A (every target met there first, then by smallest margin) on
   every condition of the block's specs, plus every other spec short or near its target at its
   start's worst condition (the specs the block's knobs may move too: settling through the AFE,
   power through its bias; a deck the block does not change is read from the cache) and the
   objective at the nominal condition.
4. The choice: judged on the rows of stage B the block moves (a spec equal at every point, as a
   full well at the pixel the stage holds still, is the local stage's), among the points meeting
   every target there, the best objective; else the largest smallest margin. ``close.run`` then verifies it on the whole grid and starts
   the trust region there when it beats the start.

Every number is SPICE (``verify.run.measure_at``); nothing is interpolated between samples.
"""
from __future__ import annotations

import math

import numpy as np

from . import margins as mg

#: Measurement groups that read only some sections of a design (besides its technology and the
#: condition), and those sections: the AFE bench drives the AFE alone from ideal sources.
BENCHES = {"afe": ("afe",)}
#: Latin hypercube points per knob of the block, and at least this many.
PER_KNOB, MIN_SAMPLES = 8, 24
#: Stage A: the worst conditions per block spec at the start.
SCREEN = 4
#: Stage B: the best points of stage A simulated on every condition of the block's specs.
KEEP = 8


def block(closer) -> tuple[list[int], list[str]]:
    """(indices of the block's knobs in ``closer.space``, names of the block's specs)."""
    sections = {s for g in BENCHES.values() for s in g}
    specs = [s.name for s in closer.base.spec if set(closer.suite.groups_for([s.fig.name])) <= set(BENCHES)]
    knobs = [j for j, k in enumerate(closer.space.knobs) if k.name.split(".")[0] in sections]
    return (knobs, specs) if knobs and specs else ([], [])


def samples(closer, p, idx: list[int], n: int) -> list[np.ndarray]:
    """``n`` Latin-hypercube points over the knobs ``idx`` (the others at ``p``), snapped as written;
    seeded by ``[verify] seed``: the same design explores the same points."""
    from scipy.stats import qmc
    lo, hi = closer.space.u_bounds
    u0 = closer.space.to_u(p.x)
    lhs = qmc.LatinHypercube(d=len(idx), seed=closer.base.verify.seed).random(n)
    out = []
    for row in lhs:
        u = u0.copy()
        u[idx] = lo[idx] + row * (hi[idx] - lo[idx])
        x = closer.space.snap(closer.space.to_x(u))
        if not any(np.array_equal(x, y) for y in out) and not np.array_equal(x, p.x):
            out.append(x)
    return out


def _short(closer, margins: dict) -> float:
    """The smallest margin less its target over ``margins`` (-inf for one not measured)."""
    return min(((-math.inf if m is None else m - closer.target(k)) for k, m in margins.items()), default=math.inf)


def _simulate(closer, xs, pairs, desc: str, objective: bool = False) -> list[tuple[dict, float | None]]:
    """({(spec, condition): margin}, objective) of each point of ``xs`` at ``pairs``."""
    groups = closer.groups(pairs)
    if objective and closer.objective.figure:
        groups.setdefault(closer.nominal, ())
        groups[closer.nominal] = tuple(sorted(set(groups[closer.nominal])
                                              | set(closer.suite.groups_for([closer.objective.figure])),
                                              key=list(closer.suite.GROUPS).index))
    conds = sorted(groups)
    designs = [closer.space.design(closer.base, x) for x in xs]
    figs = closer.at(designs, conds, groups, desc)
    out = []
    for d, f in zip(designs, figs):
        m = {(n, c): mg.margin(closer.spec[n], f.get(c, {}).get(closer.spec[n].fig.name)) for n, c in pairs}
        out.append((m, closer.objective_value(d, f.get(closer.nominal)) if objective else None))
    return out


def explore(closer, p) -> tuple[np.ndarray | None, dict]:
    """The global stage from the grid-verified start ``p``: (the chosen knob values or None when there
    is no block, a record of what was simulated)."""
    idx, specs = block(closer)
    if not idx:
        return None, {}
    n = closer.settings.global_samples
    if n == 0:
        return None, {}
    names = [closer.space.knobs[j].name for j in idx]
    n = n if n > 0 else max(MIN_SAMPLES, PER_KNOB * len(idx))
    xs = [p.x] + samples(closer, p, idx, n)
    # stage A: the block's specs at their worst conditions at the start, and the nominal one
    screen = set()
    for name in specs:
        rows = sorted(((m if m is not None else -math.inf, c) for (s, c), m in p.margins.items() if s == name),
                      key=lambda mc: (mc[0], mc[1]))
        screen |= {(name, c) for _m, c in rows[:SCREEN]}
        if (name, closer.nominal) in p.margins:
            screen.add((name, closer.nominal))
    screen = sorted(screen)
    closer.tell(f"global stage: {len(xs) - 1} samples of {', '.join(names)} at {len({c for _s, c in screen})} "
                "conditions")
    a = _simulate(closer, xs, screen, "global stage A")
    score = [_short(closer, m) for m, _f in a]
    order = sorted(range(len(xs)), key=lambda i: -score[i])
    keep = order[:KEEP]
    if 0 not in keep:
        keep.append(0)    # the start, for comparison on the same rows
    # stage B: every condition of the block's specs, the other specs near or below target where they
    # were worst at the start, the objective
    full = [k for k in p.margins if k[0] in specs]
    others = [(name, c) for name, (m, c) in mg.worst(closer.base, p.margins).items()
              if name not in specs and c is not None and (m is None or m - closer.target((name, c)) <= mg.ACTIVE)]
    pairs = sorted(set(full) | set(others))
    b = _simulate(closer, [xs[i] for i in keep], pairs, "global stage B", objective=True)
    # judged on the rows the block moves: a spec it does not (a full well, at a pixel the stage holds
    # still) is the same at every point and is the local stage's to close
    moved = [k for k in pairs if len({None if m[k] is None else round(m[k], 12) for m, _f in b}) > 1]
    rows = []
    for i, (m, f) in zip(keep, b):
        rows.append({"i": i, "short": _short(closer, {k: m[k] for k in moved}), "objective": f,
                     "knobs": {k: v for k, v in closer.space.overrides(xs[i]).items() if k in names}})
    passing = [r for r in rows if r["short"] >= 0 and r["objective"] is not None]
    if passing:
        sign = 1 if closer.objective.sense == "min" else -1
        best = min(passing, key=lambda r: sign * r["objective"])
    else:
        best = max(rows, key=lambda r: r["short"])
    record = {"knobs": names, "specs": specs, "samples": len(xs) - 1,
              "screen": [(s, c.label) for s, c in screen], "stage_a_passing": sum(s >= 0 for s in score),
              "stage_b": [{**r, "short_pct": 100 * r["short"] if math.isfinite(r["short"]) else None}
                          for r in rows], "chosen": best["i"], "start_kept": best["i"] == 0}
    for r in record["stage_b"]:
        r.pop("short")
    closer.say(f"close{closer.label}: global stage over {', '.join(names)}: {len(xs) - 1} samples, "
               f"{record['stage_a_passing']} meet {', '.join(specs)} at its worst start conditions; "
               f"{len(passing)} of the best {len(rows)} meet every target they move (the bench's whole grid, the "
               "other specs at their worst start conditions)"
               + ("; the start is kept" if best["i"] == 0 else
                  "; chosen: " + ", ".join(f"{k} = {v}" for k, v in best["knobs"].items())))
    return (None if best["i"] == 0 else xs[best["i"]]), record
