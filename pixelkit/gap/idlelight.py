"""Readout light while the readout idles: the response of the ``readout_light_idle`` effect.

The light map (``layout.pex.light``) found where a chip with its readout open to light collects its
error: not on the AFE's virtual ground during the row (``readout_light``), but on the readout's
floating nodes while it idles before its first row - samplers open, the AFE unclocked: the column
circuit's sampling node (the AFE input ``in_<col>``, between S1X / S2X and C11) and the AFE's
island (``vm``, ``x``, ``c``) float on their junctions and on each other through C11 - C13. A net
photocurrent into them (P+ in an n-well wins over N+) lifts them over the idle time; when the row
starts, p1 pulls the island back to Vref and S1X dumps the sampling node on the column line, which
the column load's current cannot pull back down within the signal sample: hundreds of mV. The
error depends on how the light is split between the sampling node and the island (the island
rising with the node takes C11's charge with it), so the effect lights the nodes the layout leaves
open with the layout's areas (``design.post_layout.open_readout``: ``layout.pex.light``'s
map of the drawn shield) and fits one figure, their total area: each junction carries
``a J area_j / A`` (A the column's open area, J the row's irradiance as a photocurrent density).

The response is measured, not derived: the nominal deck with that pattern of currents at a total
``I`` (A) on every column for the whole deck - the window and the nodes the light map lights - at
``IDLE_Q_PICK`` charges and the currents ``IDLE_I``, each deck against the same deck without it
(pixel probe: the column's sampled signal level; AFE probe: the output at the reset sample). The
table is interpolated linearly in the signal (clipped) and in ``log10(1 + I / I0)`` (the response
is a step in log I: the current at which the sampling node passes the column's level), constant
beyond the largest current (the nodes clamp on their junctions). A design without a drawn layout
(no ``post_layout``) or with nothing open has no table: the effect is not a candidate.

The idle time is the bench's: reset, the experiment's window and the wait before the first row
(``timings(design, t_window).row(0)``), the time the surrogate and the virtual silicon simulate;
a chip idling through a longer exposure collects more charge at the same irradiance.
"""
from __future__ import annotations

import numpy as np

IDLE_Q_PICK = (2, 5, 8, 11, 13, 16, 20)
I0 = 1e-15
#: total currents (A) on a column's open nodes: dense where the sampling node reaches the column's level
IDLE_I = (1e-14, 3e-14, 6e-14, 1e-13, 1.5e-13, 2.5e-13, 4e-13, 4.7e-13, 5.2e-13, 5.7e-13, 6.3e-13, 7e-13, 1.2e-12,
          3e-12, 1e-11, 1e-10, 1e-9)


def _cols(design) -> tuple:
    return ("col_p", *(f"col_s{k}" for k in range(design.secondary_per_pixel)))


def pattern(design) -> dict:
    """{column: ((node, kind, share), ...)}: the open junctions of each column's readout, each its share of
    the column's open area (top-level bench nodes, or ``scafe.<node>`` inside the column's AFE); {} when the
    design carries no layout's map or nothing is open."""
    pl = getattr(design, "post_layout", None)
    if pl is not None:
        pl.require_afe("the readout's open junctions")
    js = pl.open_readout if pl is not None else ()
    out = {}
    for c in _cols(design):
        mine = [(n, k, a) for n, k, a in js if n in (f"in_{c}", c) or n.startswith("scafe.")]
        total = sum(a for _, _, a in mine)
        if total > 0:
            out[c] = tuple((n, k, a / total) for n, k, a in mine)
    return out


def light(net, pat: dict, currents: dict):
    """``net`` (specialised: one AFE copy per column) with each column's total ``currents[col]`` (A) spread
    over its open junctions (``pattern``): P+ pushes it into its node, N+ draws it out."""
    from dataclasses import replace

    from ..spice.netlist import Element
    from .circuit_edits import add_to_subckt
    top = []
    for c, i in currents.items():
        inner = []
        for k, (node, kind, share) in enumerate(pat[c]):
            local = node.split(".", 1)[1] if node.startswith("scafe.") else node
            pins = ("vdd", local) if kind == "psd" else (local, "0")
            (inner if node.startswith("scafe.") else top).append(Element(f"Iidle_{c}_{k}", pins, i * share))
        if inner:
            net = add_to_subckt(net, f"scafe_{c}", *inner)
    return replace(net, elements=net.elements + tuple(top))


def decks(design, q_grid: dict, q_pick=IDLE_Q_PICK, currents=IDLE_I) -> list:
    """[(grid index, {column: current}, netlist)]: per picked charge, a deck without light and one per
    current (the primary's column at it, the secondaries' at the currents a third and two thirds along)."""
    from ..circuits.testbench import dual_pixel_bench
    from .chains import edge_resolved
    from .circuit_edits import specialise
    t_w = design.experiment.t_window
    pat = pattern(design)
    cols, n = _cols(design), len(currents)
    out = []
    for k in q_pick:
        qp, qs = q_grid["primary"][k], q_grid["secondary"][k]
        for j in range(-1, n):
            cur = {} if j < 0 else {c: currents[(j + m * n // len(cols)) % n] for m, c in enumerate(cols)}
            net = edge_resolved(specialise(dual_pixel_bench(design, qp / t_w, qs / t_w, with_afe=True,
                                                            title=f"gapidle{k}_{j + 1}"), design.secondary_per_pixel), design)
            out.append((k, cur, light(net, pat, cur)))
    return out


def table(design, plan: list, results: list) -> dict:
    """Per array: (signal grid V, current grid A incl. 0, pixel-probe shift V, AFE shift V) from ``decks``'s runs."""
    from ..circuits.testbench import timings
    from ..measure.pixel import levels
    tm = timings(design, design.experiment.t_window)
    base, pts = {}, {}
    for (k, cur, _), r in zip(plan, results):
        for c in _cols(design):
            arr = "primary" if c == "col_p" else "secondary"
            t = tm[arr]
            v_sig, v_rst = levels(r, c, t)
            out = float(r.at(f"out_{c}", t.t_reset_level(0)))
            if not cur:
                base[(k, c)] = (v_sig, v_rst, out)
                continue
            b = base[(k, c)]
            pts.setdefault((arr, k, cur[c]), []).append((v_sig - b[0], out - b[2]))
    res = {}
    for arr in ("primary", "secondary"):
        ks = sorted({k for a, k, _ in pts if a == arr})
        ig = np.array(sorted({i for a, _, i in pts if a == arr} | {0.0}))
        sg = np.array([np.mean([base[(k, c)][1] - base[(k, c)][0] for c in _cols(design)
                                if (c == "col_p") == (arr == "primary")]) for k in ks])
        tab = [[np.mean(pts.get((arr, k, i), [(0.0, 0.0)]), axis=0) for i in ig] for k in ks]
        tab = np.array(tab)
        res[arr] = (sg, ig, tab[:, :, 0], tab[:, :, 1])
    return res


def build(design, q_grid: dict, backend: str = "batch") -> dict | None:
    """The table of ``design`` (None: no layout's map of open junctions)."""
    from .exact import simulate_exact
    if len(pattern(design)) < len(_cols(design)):
        return None
    plan = decks(design, q_grid)
    return table(design, plan, simulate_exact([p[2] for p in plan], backend=backend))


def _s(i):
    return np.log10(1.0 + np.abs(i) / I0)


def response(tables: dict, arr_idx, signal, current) -> tuple:
    """(pixel-probe shift, AFE shift) of a total current ``current`` (A) on each row's open readout nodes over
    the idle window: the measured table, interpolated (module docstring)."""
    pix, afe = np.zeros_like(signal, dtype=float), np.zeros_like(signal, dtype=float)
    for a, arr in enumerate(("primary", "secondary")):
        m = arr_idx == a
        if not m.any():
            continue
        sg, ig, tp, ta = tables[arr]
        s = _s(np.clip(current[m], ig[0], ig[-1]))
        sig = np.clip(signal[m], sg[0], sg[-1])
        for tab, dst in ((tp, pix), (ta, afe)):
            rows = np.array([np.interp(s, _s(ig), tab[j]) for j in range(len(sg))])
            if len(sg) == 1:
                dst[m] = rows[0]
                continue
            j = np.clip(np.searchsorted(sg, sig) - 1, 0, len(sg) - 2)
            w = (sig - sg[j]) / (sg[j + 1] - sg[j])
            idx = np.arange(sig.size)
            dst[m] = rows[j, idx] * (1 - w) + rows[j + 1, idx] * w
    return pix, afe
