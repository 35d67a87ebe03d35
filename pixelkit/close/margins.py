"""Each spec's margin at each condition, in units of its limit, and the conditions that bind.

The margin of a value v against a spec is the distance to the nearer limit, as the sign-off
table states it, divided by that limit's size: min((v - min) / |min|, (max - v) / |max|)
(0.05 = 5 % of the limit inside, -0.1 = 10 % outside; a limit of 0 is measured against the
other limit's size, or the spec's ``typ``, or the figure's display unit). All specs are then
comparable, and "the smallest margin" (the worst spec at its worst condition) is one number:
what close raises when the design fails and keeps >= ``[close] margin`` while optimising.
"""
from __future__ import annotations

import math

from ..verify.conditions import spec_conditions
from ..verify.figures import unit_scale

#: Per spec, the conditions modelled: its worst and those whose margin is within BAND of it
#: (at most PER_SPEC); only specs whose worst margin is within ACTIVE of its target.
PER_SPEC = 2
BAND = 0.05
ACTIVE = 0.10


def _size(spec, limit) -> float:
    for x in (limit, spec.hi if limit is spec.lo else spec.lo, spec.typical):
        if x:
            return abs(x)
    kind, scale = unit_scale(spec.shown_unit, spec.fig.dim)
    return scale if kind == "lin" else 0.01


def margin(spec, v: float | None) -> float | None:
    """The normalised margin of value ``v`` (SI); None when not measured."""
    if v is None or not math.isfinite(v):
        return None
    out = math.inf
    if spec.lo is not None:
        out = min(out, (v - spec.lo) / _size(spec, spec.lo))
    if spec.hi is not None:
        out = min(out, (spec.hi - v) / _size(spec, spec.hi))
    return out


def table(design, grid, values: dict) -> dict:
    """{(spec name, condition): normalised margin or None} over each spec's conditions of ``grid``;
    ``values``: {condition: {figure: SI value}}."""
    out = {}
    for s in design.spec:
        for c in spec_conditions(s, grid):
            out[(s.name, c)] = margin(s, values.get(c, {}).get(s.fig.name))
    return out


def worst(design, margins: dict) -> dict:
    """{spec: (margin, condition)} of each spec's worst measured condition (None, None: none measured)."""
    out = {s.name: (None, None) for s in design.spec}
    for (name, c), m in margins.items():
        if m is not None and (out[name][0] is None or m < out[name][0]):
            out[name] = (m, c)
    return out


def smallest(margins: dict, targets: dict | None = None) -> float:
    """The smallest margin over all pairs, each less its target (-inf when one was not measured)."""
    targets = targets or {}
    vals = [(m - targets.get(k, 0.0)) if m is not None else -math.inf for k, m in margins.items()]
    return min(vals) if vals else math.inf


def binding(design, margins: dict, targets: dict | None = None, default_target: float = 0.0) -> list:
    """The (spec, condition) pairs to model: per spec whose worst margin is within ACTIVE of its target
    (or below it), its worst condition and up to PER_SPEC - 1 others within BAND of it. A spec with
    more margin than that is not modelled: every candidate is verified on the whole grid, and a spec
    that fails there is modelled from then on (the caller's forced pairs)."""
    targets = targets or {}
    by_spec: dict = {}
    for (name, c), m in margins.items():
        by_spec.setdefault(name, []).append((-math.inf if m is None else m - targets.get((name, c), default_target),
                                             c))
    out = []
    for name, items in by_spec.items():
        items.sort(key=lambda mc: (mc[0], mc[1]))
        w = items[0][0]
        if w > ACTIVE:
            continue
        for i, (m, c) in enumerate(items[:PER_SPEC]):
            if i == 0 or m <= w + BAND:
                out.append((name, c))
    return sorted(set(out), key=lambda p: (p[0], p[1]))
