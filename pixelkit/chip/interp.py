"""Column chains of a frame interpolated in photocurrent, checked against SPICE in every frame.

When: ``chip.frame.simulate_frame(..., interpolate=True)`` (the default of ``split="columns"``,
``pixelkit array --afe``; ``--exhaustive`` simulates every chain), for the chains of one array
whose columns each see one photocurrent in every row (a scene that varies only across the
columns: the default gradient, bars), no subpixel within ``CLIP_MARGIN`` of clipping, and more
such chains than ``ANCHORS`` + the 2 held-out ones. Everything else is simulated as before.

Why it holds: the columns of a chain share only ideal sources (``chip.frame``), so a column's
results - every row's double-sampled signal, reset level, AFE output, settling error and its two
parts - depend only on its own photocurrents and on its place in its chain (the secondary's
lines differ per place in the post-layout view). With one current per column, each is a smooth
function of that current away from clipping (the PD's and FD's junction capacitances, the
source follower's gain: no switching threshold in between), which a polynomial through a few
simulated currents follows.

How: per array, ``ANCHORS`` chains are simulated with their columns at Chebyshev-Lobatto
currents over the range of the columns at that place (the chain's own deck, its currents
replaced: the first deck of every interpolated chain must equal the anchors' once its column
numbers are renamed and its photocurrents masked, else it is simulated); every figure of every
other column is the polynomial through the anchors at its current (barycentric form), row by
row. The anchors, and the array's chains that are simulated, run at ``chip.frame.CONVERGED``
tolerances (reltol 1e-6, abstol 1e-12, ~1.25x the time of a deck): at the kit's tolerances each
chain carries its own step-sequence error, the same for the columns of one chain and different
from chain to chain (revB's gradient, 2 x 50: the exhaustive frame is up to 0.33 mV (primary)
and 1.15 mV (secondary signal) from the converged one), which a polynomial through
default-tolerance anchors would amplify. Checked in every frame: the 2 chains where the nodal
polynomial (the factor of the interpolation error) is largest are simulated as well, at the
same tolerances, and every figure of theirs compared with its interpolated value; beyond
``LIMIT_V`` (or an anchor or held-out deck that failed, or a figure an anchor could not
measure) every chain of the array is simulated after all at the kit's tolerances, as
``interpolate=False`` does (the converged runs are then not used: the array is as the
exhaustive path gives it). ``Frame.interpolated`` says per array what was done and the
held-out difference; the frame's table marks each cell ``spice`` or ``interpolated``.
On revB's 2 x 50 gradient the interpolated frame is within 0.030 mV of the frame simulated whole
at converged tolerances on every figure (docs/arrays.md).

``LIMIT_V``: 0.1 mV, the limit the kit holds its frame splits to against the undivided deck
(``tests/test_frame.py``), below the exhaustive frame's own chain-to-chain error at the kit's
tolerances (above): an interpolated figure is no further from the converged answer than a
simulated one.
"""
from __future__ import annotations

import re

import numpy as np

#: Simulated currents per interpolating polynomial (Chebyshev-Lobatto: both ends of the range included),
#: per array. On revB's gradient (2 x 50, against every column simulated at converged tolerances) the
#: largest error of any figure: primary 0.17 mV with 6, 0.069 with 7, 0.025 with 8 (its signal bends
#: towards the top of the range); secondary 0.030 with 5, 0.017 with 6, flat beyond (the converged
#: decks' own scatter). Where the places of a chain are the same circuit (``_interchangeable``) the
#: currents are spread over the places of ceil(ANCHORS / places) anchor chains (9: 3 chains of 3
#: primary columns, 6: 2 chains of 3 secondary columns), else every place has its own ANCHORS chains.
ANCHORS = {"primary": 12, "secondary": 6}
#: Largest difference (V) of any figure of a held-out chain from its interpolated value.
LIMIT_V = 1e-4
#: A column is interpolated only below this fraction of the current that clips it (``scene.i_floor``).
CLIP_MARGIN = 0.9
_CURRENT = re.compile(r"\b(iph\w*)=\S+")
#: Column numbers a chain's columns are renamed to when its places are compared (no row's or other
#: element's number is this large, so a renaming touches the columns only).
_FAR = 10 ** 7


def plan(tasks: list, kinds, design, t_exp: float, deck, converged) -> dict:
    """Which chains of ``tasks`` (``chip.frame._chain`` tasks) to interpolate, per array:
    {kind: {"anchors": [task], "x": [currents of each polynomial], "group": polynomial of each place,
    "slot": per anchor and place the current's index in its polynomial, "held_out": [index],
    "rest": [index], "cols": {index: columns}, ...}}; an array left out is simulated whole.
    ``deck(task, mine, to)``: the text of a chain's first deck, its columns ``mine`` renamed to ``to``;
    ``converged``: the simulator options the anchors and held-out chains run at, over the chain's own."""
    from .scene import i_floor
    out = {}
    n = design.secondary_per_pixel
    for kind in kinds:
        idx = [i for i, t in enumerate(tasks) if t[3].kinds == (kind,)]
        cur = np.asarray(tasks[idx[0]][1 if kind == "primary" else 2], float) if idx else None
        if cur is None:
            continue
        hi = CLIP_MARGIN * i_floor(design, kind, t_exp)
        width = max(len(tasks[i][3].columns(kind, n)) for i in idx)
        cols = {i: tasks[i][3].columns(kind, n) for i in idx}
        flat = [i for i in idx if all(np.all(cur[:, j] == cur[0, j]) and 0 <= cur[0, j] < hi for j in cols[i])]
        ok = [i for i in flat if len(cols[i]) == width]
        if len(ok) <= 3:
            continue
        probe = next((i for i in ok if 0 not in cols[i]), ok[0])
        shared = _interchangeable(lambda to: deck(tasks[probe], cols[probe], to), width)
        # the polynomials: one for every place, or one per place; their currents and the anchors'
        group = [0] * width if shared else list(range(width))
        places = [[q for q in range(width) if group[q] == g] for g in range(max(group) + 1)]
        K = ANCHORS[kind]
        chains = -(-K // width) if shared else K
        K = chains * width if shared else K
        slot = [[q * chains + a if shared else a for q in range(width)] for a in range(chains)]
        if len(ok) <= chains + 2:
            continue
        lo = [min(cur[0, cols[i][q]] for i in flat for q in qs if q < len(cols[i])) for qs in places]
        top = [max(cur[0, cols[i][q]] for i in flat for q in qs if q < len(cols[i])) for qs in places]
        if any(b <= a for a, b in zip(lo, top)):
            continue
        k = np.arange(K)
        x = [(a + b) / 2 - (b - a) / 2 * np.cos(np.pi * k / (K - 1)) for a, b in zip(lo, top)]
        ac = cols[ok[0]]     # the anchors' columns
        anchors = [_tight(_anchor(tasks[ok[0]], kind, ac, [x[group[q]][slot[a][q]] for q in range(width)], a),
                          converged) for a in range(chains)]
        ref = _masked(deck(anchors[0], ac, ac))
        ok = [i for i in ok if _masked(deck(tasks[i], cols[i], ac)) == ref]
        if len(ok) <= chains + 2 or probe not in ok:   # the places were judged on a chain the anchors are not
            continue
        # a narrower chain (the array's last, when its columns do not fill a chain): its places are the
        # anchors' first ones when its deck is the anchor chain's cut to as many columns and the places are
        # one circuit (else the cut's edge place - a coupling to the next place dropped - is not the
        # anchors' place, and a narrow chain is never held out to show it)
        narrow = [i for i in flat if shared and len(cols[i]) < width
                  and _masked(deck(tasks[i], cols[i], ac[:len(cols[i])])) == _narrow_ref(anchors[0], kind, n, cols[i], deck)]
        # held out: the two chains where an interpolation error is likeliest largest
        held = sorted(ok, key=lambda i: _nodal(cur[0], cols[i], x, group, lo, top))[-2:]
        out[kind] = {"anchors": anchors, "x": x, "group": group, "slot": slot, "shared": shared,
                     "held_out": held, "rest": [i for i in ok + narrow if i not in held],
                     # the array's chains simulated: at the anchors' tolerances, so that the array is of one accuracy
                     "tight": {i: _tight(tasks[i], converged) for i in idx if i in held or i not in ok + narrow},
                     "cols": cols, "anchor_cols": ac, "current": cur[0]}
    return out


def _interchangeable(text, width: int) -> bool:
    """Whether the places of a chain are the same circuit under other names, so that one polynomial
    serves them all: ``text(to)``, the chain's first deck with its columns renamed to ``to``, the same
    (photocurrents masked, top-level elements in any order) when every column is renamed one place on.
    (A place-dependent element - a line whose couplings differ per place, as a post-layout secondary
    can have - differs there, and every place then has its own polynomial.)"""
    if width < 2:
        return True
    a = text([_FAR + q for q in range(width)])
    b = text([_FAR + (q + 1) % width for q in range(width)])
    return _elements(_masked(a)) == _elements(_masked(b))


def _elements(text: str) -> tuple:
    """A deck's logical lines (continuations joined): subcircuit definitions and dot lines in order,
    the top-level elements sorted (their order does not change the circuit)."""
    lines = []
    for line in text.splitlines():
        if line.startswith("+") and lines:
            lines[-1] += " " + line[1:].strip()
        elif line.strip() and not line.startswith("*"):
            lines.append(line.strip())
    kept, top, depth = [], [], 0
    for line in lines:
        low = line.lower()
        depth += low.startswith(".subckt")
        (kept if depth or line.startswith(".") else top).append(line)
        depth -= low.startswith(".ends")
    return tuple(kept), tuple(sorted(top))


def _narrow_ref(anchor, kind: str, n: int, cols, deck) -> str | None:
    """The masked first deck of ``anchor``'s chain cut to its first dual-pixel columns, as many of
    ``kind``'s columns as ``cols`` holds (None when no cut holds as many)."""
    from dataclasses import replace
    tile = anchor[3]
    for m in range(1, len(tile.cols)):
        cut = replace(tile, cols=tile.cols[:m])
        mine = cut.columns(kind, n)
        if len(mine) == len(cols):
            t = list(anchor)
            t[3] = cut
            return _masked(deck(tuple(t), mine, mine))
    return None


def _nodal(cur, cols, x, group, lo, hi) -> float:
    """The largest nodal polynomial |prod_k (i - x_k)| over a chain's places (currents scaled to the
    range): the factor of the error of polynomial interpolation that depends on where ``i`` lies."""
    return max(abs(float(np.prod((cur[j] - x[group[q]]) / (hi[group[q]] - lo[group[q]])))) for q, j in enumerate(cols))


def _tight(task, converged) -> tuple:
    """``task``'s chain simulated at the options ``converged`` over its own."""
    from ..spice.options import merged
    t = list(task)
    t[9] = merged(task[9] or (), converged)
    return tuple(t)


def _anchor(task, kind: str, cols, currents, a: int) -> tuple:
    """``task``'s chain with its columns at ``currents`` (one per place, every row)."""
    pick = 1 if kind == "primary" else 2
    cur = np.array(task[pick], float)
    for j, c in zip(cols, currents):
        cur[:, j] = c
    t = list(task)
    t[pick] = cur
    t[11] = f"{task[11]}_anchor{a}"
    return tuple(t)


def _masked(text: str) -> str:
    """A deck's text with its photocurrents masked: what must be equal for two chains to differ only in
    their currents."""
    return _CURRENT.sub(r"\1=?", text)


def resolve(p: dict, kind: str, outs: dict, anchor_outs: list) -> tuple[dict | None, dict]:
    """The interpolated outs of ``p["rest"]`` ({index: out}, None when the check refuses them) and the
    array's record for ``Frame.interpolated``."""
    from scipy.interpolate import BarycentricInterpolator
    rec = {"array": kind, "anchors": len(anchor_outs), "currents": len(p["x"][0]), "places_shared": p["shared"],
           "held_out": len(p["held_out"]), "limit_V": LIMIT_V, "chains": len(p["rest"]), "max_diff_V": None,
           "used": False}
    bad = [o for o in anchor_outs + [outs[i] for i in p["held_out"]] if o["failures"]]
    if bad:
        rec["why"] = "an anchor or held-out chain failed"
        return None, rec
    ac = p["anchor_cols"]
    rows = sorted({r for (_k, r, _j) in anchor_outs[0]["values"]})
    fields = _fields(anchor_outs[0])
    # per polynomial: its currents x rows x figures, from the anchors' places
    data = [np.full((len(x), len(rows), 2 + sum(fields) + 2 * fields[1]), np.nan) for x in p["x"]]
    for a, o in enumerate(anchor_outs):
        for q, j in enumerate(ac):
            data[p["group"][q]][p["slot"][a][q]] = [_figures(o, (kind, r, j), fields) for r in rows]
    if not all(np.all(np.isfinite(d)) for d in data):
        rec["why"] = "an anchor figure was not measured"
        return None, rec
    poly = [BarycentricInterpolator(x, d) for x, d in zip(p["x"], data)]

    def cells(i):
        return {(kind, r, j): vals[ri] for q, j in enumerate(p["cols"][i])
                for vals in [poly[p["group"][q]](p["current"][j])] for ri, r in enumerate(rows)}
    worst = 0.0
    for i in p["held_out"]:
        for key, v in cells(i).items():
            fresh = np.array(_figures(outs[i], key, fields), float)
            if not np.all(np.isfinite(fresh)):
                rec["why"] = "a held-out figure was not measured"
                return None, rec
            worst = max(worst, float(np.max(np.abs(fresh - v))))
    rec["max_diff_V"] = worst
    if worst > LIMIT_V:
        rec["why"] = "held-out chains beyond the limit"
        return None, rec
    rec["used"] = True
    return {i: _out(cells(i), fields) for i in p["rest"]}, rec


def _fields(out) -> tuple:
    """The figures a chain's out holds: (AFE output measured, settling measured)."""
    first = next(iter(out["values"].values()))
    return first[2] is not None, bool(out.get("settling"))


def _figures(out, key, fields) -> list:
    """signal, reset level[, AFE output][, settling error and its two parts] of cell ``key``."""
    s, rst, afe = out["values"][key]
    v = [s, rst, *([afe] if fields[0] else [])]
    if fields[1]:
        v += [out["settling"][key], *out["parts"][key]]
    return [np.nan if x is None else x for x in v]


def _out(cells: dict, fields) -> dict:
    """An interpolated chain's out, as ``chip.frame._chain`` gives a simulated one's."""
    a = 3 if fields[0] else 2
    out = {"failures": [], "retried": [], "decks": 0, "notes": [],
           "values": {k: (float(v[0]), float(v[1]), float(v[2]) if fields[0] else None) for k, v in cells.items()}}
    if fields[1]:
        out["settling"] = {k: float(v[a]) for k, v in cells.items()}
        out["parts"] = {k: (float(v[a + 1]), float(v[a + 2])) for k, v in cells.items()}
    return out
