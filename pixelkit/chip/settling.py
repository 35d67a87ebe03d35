"""Settling of a frame's reads: each double-sampled signal against the same read with long S1 and S2.

A row's signal level is what the column (and C11, with the AFE) holds when S1 opens, its
reset level what it holds when S2 opens. If the column is still moving then, the sample
depends on where the column came from (the previous row's reset level, the signal level
before the reset) instead of on the pixel: the frame's row-to-row memory.

The reference is a different operating point of the same circuit, not the code under
test checking itself: the same deck of the same row, started from the same column state
(the chain's hand-over), with S1 and S2 each held closed ``LONG_S1`` row times longer (the
phases after each move by as much). Up to the instant the two reads part (:func:`parting`:
the AFE's phase 1 opening ahead of the read's S1) the reference deck is the read's deck, so
that part is not simulated again: the reference starts there (:func:`shifted`) from the read's
state (every node that holds charge: the column's hand-over nodes and the row's pixels,
:func:`pixel_nodes`, as initial conditions) and stops at its reset-level sample; at converged
tolerances its settling errors are those of the whole reference deck within 0.008 mV
(``dual_pixel_revA`` and its [Thesis2019] read, column chains and row decks). At the end of a long
phase the column has long
settled and only drifts with the storage node (parasitic light and leakage on FD, a
straight line over microseconds). The settled level at the real sample instant is the
reference's sample taken back along that line (to the same time after S1 closes, or after
RST opens): two slopes over the last 2.5 row times of the long phase (ending half a row
before it, ahead of the kick the AFE's phase 1 gives C11 when it opens) give the line and
tell whether the reference itself has settled (they must agree within ``limit / 4`` over
the extrapolation; if not, the cell is not measured and a note says so).

The settling error of a subpixel is its double-sampled signal (reset level - signal level)
minus the settled one (V): negative when the read gives too small a signal.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..spice.netlist import Pulse, Pwl

#: The reference read's S1 is this many row times longer (slew capacity at the reference
#: design's 400 nA on 700 fF over 4 x 2 us: 4.6 V, three times the pixel's swing).
LONG_S1 = 4
#: Default limit on |settling error| (V), as the issue and the report state it.
LIMIT_V = 0.5e-3
_SHIFTED = (("s1_off", 1), ("rst_on", 1), ("rst_off", 1), ("s2_on", 1), ("s2_off", 2), ("rs_off", 2))


def long_s1(t, factor: float | None = None):
    """The timing ``t`` with S1 and S2 each ``factor`` (default ``LONG_S1``) row times longer,
    the phases after them moved by as much."""
    d = (LONG_S1 if factor is None else factor) * t.t_row
    phases = {k: t.phase(k) for k in ("rs_on", "s1_on", *(("pre_on", "pre_off") if t.precharged else ()))}
    phases.update({k: t.phase(k) + n * d for k, n in _SHIFTED})
    return replace(t, phases=tuple(phases.items()))


def reference_timings(tm: dict, kind: str, factor: float | None = None) -> dict:
    return {k: (long_s1(t, factor) if k == kind else t) for k, t in tm.items()}


#: A subpixel's own nodes that hold charge (``circuits.pixel5t``: PD, FD, SF output).
PIXEL_STATE = ("pd", "fd", "sfo")


def pixel_nodes(kind: str, row: int, columns) -> list[str]:
    """The state nodes of row ``row``'s subpixels of ``kind`` in ``columns`` (``circuits.array``)."""
    s = "p" if kind == "primary" else "s"
    return [f"x{s}_{row}_{j}.{n}" for j in columns for n in PIXEL_STATE]


def parting(a, b) -> float:
    """The last instant (s) up to which decks ``a`` and ``b`` are the same circuit under the same
    sources: every element, subcircuit, model, include and option equal, PWL sources equal up to
    that breakpoint. A ValueError when they differ in anything else."""
    same = ("subckts", "models", "includes", "options", "temperature_C")
    ea, eb = {e.name: e for e in a.elements}, {e.name: e for e in b.elements}
    if ea.keys() != eb.keys() or any(getattr(a, f) != getattr(b, f) for f in same):
        raise ValueError(f"decks {a.title} and {b.title} are not the same circuit")
    t = float("inf")
    for name, x in ea.items():
        y = eb[name]
        if x == y:
            continue
        waves = isinstance(x.value, Pwl) and isinstance(y.value, Pwl)
        if not (waves and replace(x, value=None) == replace(y, value=None)):
            raise ValueError(f"element {name} differs between {a.title} and {b.title} beyond its waveform")
        t = min(t, _apart(x.value.points, y.value.points))
    return t


def shifted(net, t: float, stop: float):
    """Deck ``net`` from its instant ``t`` to ``stop`` (s), as a deck whose time 0 is ``t``: every PWL
    source moved by ``-t`` (its value at ``t`` first; a constant if it has no later point). A
    ValueError for any other time-dependent source."""
    els = []
    for e in net.elements:
        if isinstance(e.value, Pwl):
            pts = e.value.points
            v0 = float(np.interp(t, *zip(*pts)))
            later = tuple((a - t, v) for a, v in pts if a > t)
            e = replace(e, value=Pwl(((0.0, v0), *later)) if later else v0)
        elif isinstance(e.value, Pulse):
            raise ValueError(f"element {e.name} of {net.title}: only PWL sources can be shifted in time")
        els.append(e)
    return replace(net, elements=tuple(els), analysis=replace(net.analysis, stop=stop - t))


def _apart(p, q) -> float:
    """The last breakpoint up to which the PWL waveforms ``p`` and ``q`` ((t, v), ...) agree."""
    ts = np.union1d([t for t, _ in p], [t for t, _ in q])
    va = np.interp(ts, *zip(*p))
    vb = np.interp(ts, *zip(*q))
    if (va == vb).all():
        return float("inf")
    k = int(np.argmax(va != vb))
    return float(ts[k - 1]) if k else 0.0


def settled_level(res, node: str, t_ref, t, row: int, limit: float = LIMIT_V, which: str = "signal"):
    """(settled level at ``t``'s sample instant, whether the reference has settled);
    ``which``: the signal level (end of S1) or the reset level (end of S2).

    The reference's own sample (at the end of its long S1 or S2, with the kick the AFE's
    phase 1 gives C11 when it opens just before S1 does) minus the column's drift over the
    extra time since the last event (S1 on, or RST off): the slope of its straight line over
    [end - 2.5, end - 0.5] row times, before that kick."""
    if which == "signal":
        t1, d = t_ref.t_signal(row), t_ref.t_signal(row) - t.t_signal(row)
    else:
        t1 = t_ref.t_reset_level(row)
        d = (t1 - t_ref.rst_window(row)[1]) - (t.t_reset_level(row) - t.rst_window(row)[1])
    q = t.t_row
    v0, v1, v2 = (float(res.at(node, t1 - (k + 0.5) * q)) for k in (2, 1, 0))
    slope, before = (v2 - v1) / q, (v1 - v0) / q
    return float(res.at(node, t1)) - slope * d, abs(slope - before) * d <= limit / 4


def limits(design, override: float | None = None) -> dict:
    """Per array, the largest settling error accepted (V): ``override``, else the design's
    ``[spec.settling_<array>]`` max, else ``LIMIT_V``."""
    specs = {s.name: s for s in getattr(design, "spec", ()) or ()}
    out = {}
    for kind in ("primary", "secondary"):
        s = specs.get(f"settling_{kind}")
        out[kind] = override if override is not None else (s.hi if s is not None and s.hi is not None else LIMIT_V)
    return out


def summary(errors: dict, limit=LIMIT_V) -> dict:
    """The settling figure of a frame: worst |error| per array (V), the subpixels beyond the
    limit (V, or per array a dict) as (row, column) lists, and cells not measured."""
    lim = limit if isinstance(limit, dict) else {k: limit for k in errors}
    out = {"limit_V": lim, "worst_V": {}, "beyond": {}, "not_measured": 0}
    for kind, e in errors.items():
        limit = lim[kind]
        e = np.asarray(e, float)
        out["not_measured"] += int(np.isnan(e).sum())
        out["worst_V"][kind] = float(np.nanmax(np.abs(e))) if np.isfinite(e).any() else None
        out["beyond"][kind] = [[int(r), int(c)] for r, c in zip(*np.nonzero(np.abs(np.nan_to_num(e)) > limit))]
    return out


def describe(s: dict, most: int = 8) -> list[str]:
    """Lines naming the rows and columns beyond the limit, per array."""
    lines = []
    for kind, cells in s["beyond"].items():
        if not cells:
            continue
        rows = sorted({r for r, _ in cells})
        cols = sorted({c for _, c in cells})
        lines.append(f"{kind}: {len(cells)} subpixel(s) beyond {s['limit_V'][kind] * 1e3:g} mV, rows "
                     f"{_span(rows, most)}, columns {_span(cols, most)}")
    return lines


def _span(xs, most):
    return ", ".join(map(str, xs[:most])) + (f" ... ({len(xs)})" if len(xs) > most else "")
