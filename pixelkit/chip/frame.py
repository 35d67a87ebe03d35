"""One frame of the pixel arrays, simulated whole or split into independent decks.

What is independent (and why a split is exact up to the simulator's numerics):

- the two arrays have their own control lines and column buses, and every column its
  own load bias generator (an ideal current into a diode-connected NMOS): arrays and
  columns share only ideal sources (supplies, row lines, clocks). (One bias node per
  array couples its columns through the loads' Cgd while they slew, 0.1 - 0.16 mV, which
  no split could keep);
- during exposure every pixel is on its own; during read-out only the selected row
  drives a column (the other rows' RS switches are off: one device per column stands in
  for them, ``m`` = their count).

What is not: a column remembers its earlier rows. With the AFE, C11's input keeps the
previous row's reset level until S1X closes, and for large signals the column does not
settle within S1, so a row's signal depends on it; and the next row's pixel, though not
selected, sees the line through its RS switch, whose leakage sets where that pixel's
source-follower output rests, charge that reaches FD when RS closes.

``split="columns"`` (the default with the AFE): one chain of decks per array and group of
columns (``GROUP`` dual-pixel columns: 3 primary, or the N secondary columns of one), one
deck per row. A row's
deck holds that row's subpixels, the off-row device, the columns' loads, samplers and
AFEs, and the row's own controls at its time in the frame. The state the earlier rows
leave is handed over (:class:`~pixelkit.circuits.array.Handoff`): the previous row's deck
gives each state node's voltage at the row's start (column line, C11's input, the AFE's
floating nodes and op-amp state, the bias and off-row nodes), the deck holds its nodes
there through switches that open at that instant, and the column line is held at its own
history before (at rest until the first row selects it). A row costs one row read, and
chains run in parallel. Checked against the undivided deck: every row of a 27-row
column within 0.013 mV (primary) / 0.038 mV (secondary); holding the line at the
hand-over value from t = 0 instead left a dim pixel 2.2 mV off, re-simulating the
previous row as a lead (the former row split) 0.39 mV off from the third row on.

Identical chains (``reuse=True``, the default): two chains of the same array whose columns see
the same photocurrents in every row (a uniform scene, a flat field, a dark or saturated band) are
the same circuit under other names, since columns share only ideal sources. The later one is not
simulated; its cells take the earlier chain's values, after a check: the photocurrents of every row
equal bit for bit, and the first row's deck text the same once its column numbers are renamed to the
earlier chain's (a column-dependent element, a Monte Carlo draw or an extracted view per column
would differ there, and the chain is then simulated). ``Frame.reused`` lists them.

``split="rows"`` (the default without the AFE): one deck per array and row with all its
columns (no AFE, no memory beyond the line, which the row's own RS resets; 27-row column
within 0.011 mV of the undivided deck). Refused with the AFE.

Settling (``settling=True``, ``chip.settling``): every row's deck is read a second time with
long S1 and S2 from the same hand-over (``columns``) or alone (``rows``), and each
subpixel's double-sampled signal is compared with that settled read. The second read is the
first up to the instant the two part, so it starts there from the first read's state (whose
deck saves the row's pixel nodes too) instead of simulating the exposure and the row's start
again (``_continued``).

``split="none"``: each array as one deck, every row and column (the reference;
``tests/test_frame.py`` and ``pixelkit array --check`` compare the splits with it, and a
Monte Carlo frame runs so). The arrays share only ideal sources, so one deck per array is
the whole frame's circuit; both arrays in one deck only add the simulator's noise of two
interleaved row clocks in one step sequence (up to 0.11 mV at reltol 1e-6).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from functools import partial

import numpy as np

from ..circuits.array import (KINDS, PREFIX, Handoff, Tile, array_bench, frame_shape, frame_timings,
                              state_nodes)
from ..errors import ConfigError, SimulationError
from ..spice.executors import run_tasks

SPLITS = ("columns", "rows", "none")
#: Dual-pixel columns per deck of a column chain: 3 primary, or 1 (3 secondary columns).
GROUP = {"primary": 3, "secondary": 1}
#: Largest time step of a frame deck: half the shorter row time (0.5 us for 1 MHz), as the
#: long benches. PWL edges are breakpoints, so switching is still resolved; between them the
#: error control steps. On a 27-row primary column with its AFE (default tolerances) against
#: the converged undivided deck: largest error 0.13 mV at t_row / 2, 0.24 mV at t_row / 20
#: (the error is the tolerances', not the step's), in 0.7x the time (docs/arrays.md).
STEPS_PER_ROW = 2


@dataclass
class Frame:
    """Per-subpixel results of one frame (V): ``signal`` = reset level - signal level on
    the column; ``afe`` = the AFE output at the end of its phase 2 (with_afe only)."""
    rows: int
    cols: int
    signal: dict            # kind -> rows x cols array (V)
    reset_level: dict       # kind -> array (V): the column's reset level (before DS)
    afe: dict               # kind -> array (V) or empty
    decks: int              # decks simulated (a failed chain's later rows are not)
    wall_s: float
    split: str
    failures: list = field(default_factory=list)
    retried: list = field(default_factory=list)   # decks the engine re-ran with looser options
    #: kind -> rows x cols array (V): the double-sampled signal minus that of the same read with
    #: long S1 and S2 (``chip.settling``); NaN where not measured; empty: not measured
    settling: dict = field(default_factory=dict)
    settling_notes: list = field(default_factory=list)
    #: kind -> rows x cols x 2 (V): the sampled signal level's and reset level's own errors
    #: (sampled - settled; the settling error is the second minus the first)
    settling_parts: dict = field(default_factory=dict)
    #: column chains not simulated, each identical to an earlier one: {"chain": title, "from": title}
    reused: list = field(default_factory=list)
    #: per array whose chains were interpolated in photocurrent, or tried (``chip.interp``): anchors,
    #: held-out chains, chains interpolated, the held-out difference and its limit, used or why not
    interpolated: list = field(default_factory=list)

    def settling_summary(self, limit=None) -> dict | None:
        """``limit``: V, or per array a dict (default ``settling.LIMIT_V``)."""
        from .settling import LIMIT_V, summary
        if not self.settling:
            return None
        return {**summary(self.settling, LIMIT_V if limit is None else limit), "notes": self.settling_notes}

    def as_dict(self) -> dict:
        out = {"rows": self.rows, "cols": self.cols, "split": self.split, "decks": self.decks,
               "wall_s": self.wall_s, "failures": self.failures, "retried": self.retried,
               **({"reused": self.reused} if self.reused else {}),
               **({"interpolated": self.interpolated} if self.interpolated else {})}
        for k in KINDS:
            out[f"{k}_signal_V"] = _listed(self.signal[k])
            out[f"{k}_reset_level_V"] = _listed(self.reset_level[k])
            if k in self.afe:
                out[f"{k}_afe_out_V"] = _listed(self.afe[k])
            if k in self.settling:
                out[f"{k}_settling_V"] = _listed(self.settling[k])
        out["settling"] = self.settling_summary()
        return out


def _listed(a: np.ndarray) -> list:
    """Nested lists with None where a deck failed (JSON has no NaN)."""
    return [[None if v != v else float(v) for v in row] for row in a]


def tiles(rows: int, cols: int, split: str, with_afe: bool = False, kinds=KINDS) -> list[Tile]:
    """The decks of a frame; for ``columns`` the first row's deck of each chain."""
    if split not in SPLITS:
        raise ConfigError("", "split", split, f"one of {', '.join(SPLITS)}")
    if split == "columns":
        return [Tile((k,), (0,), tuple(range(c, min(c + GROUP[k], cols)))) for k in kinds
                for c in range(0, cols, GROUP[k])]
    if split == "none":
        return [Tile((k,), tuple(range(rows)), tuple(range(cols))) for k in kinds]
    if with_afe:
        raise ConfigError("", "split", split, "columns or none with the AFE (a deck per row cannot carry "
                          "the column's memory of the earlier rows)")
    return [Tile((k,), (r,), tuple(range(cols))) for k in kinds for r in range(rows)]


def _probes(design, tile: Tile, tm: dict, with_afe: bool) -> list:
    n = design.secondary_per_pixel
    return [((k, r, j), f"col_{PREFIX[k]}_{j}", tm[k], r, f"out_col_{PREFIX[k]}_{j}" if with_afe else None)
            for k in tile.kinds for r in tile.rows for j in tile.columns(k, n)]


def _saved(net, probes, nodes=()):
    """Only the vectors the frame reads (probes, hand-over nodes) go to the raw file and cache."""
    keep = dict.fromkeys([*(p[1] for p in probes), *(p[4] for p in probes if p[4]), *nodes])
    return replace(net, saves=tuple(keep))


def _read(res, probes) -> dict:
    from ..measure.pixel import levels
    out = {}
    for key, node, timing, row, afe_node in probes:
        sig, rst = levels(res, node, timing, row)
        out[key] = (rst - sig, rst, float(res.at(afe_node, timing.t_reset_level(row))) if afe_node else None)
    return out


def _retried(res):
    return res.meta["retried"]["reason"] if res.meta.get("retried") else None


def _run_one(net, backend, jobs, options, settle: bool):
    """One deck through the engine. A deck whose settling is measured and that only ran at the
    engine's looser retry options (reltol 1e-4: a noise floor near the 0.5 mV limit) is run
    again at ``CONVERGED`` tolerances, which the stiff edges that stopped it usually pass."""
    from ..spice import simulate_many
    from ..spice.options import merged
    res = simulate_many([net], backend=backend, jobs=jobs, options=options)[0]
    if settle and _retried(res):
        tight = simulate_many([net], backend=backend, jobs=jobs, options=merged(options or (), CONVERGED))[0]
        if not _retried(tight):
            return tight
    return res


def _probe(task):
    """Simulate one tile (through the engine and its cache) and read its samples; with a
    reference (``ref``: the same tile read with long S1 and S2, see :func:`_continued`), their
    settling errors."""
    net, backend, jobs, options, probes, ref = task
    out = {"failures": [], "retried": [], "values": {}, "decks": 0, "settling": {}, "notes": []}
    try:
        res = _run_one(net, backend, jobs, options, ref is not None)
    except SimulationError as exc:
        out["failures"].append({"deck": net.title, "message": exc.message})
        return out
    why = _retried(res)
    out["retried"] += [{"deck": net.title, "message": why}] if why else []
    out["values"], out["decks"] = _read(res, probes), 1
    if ref is not None:
        build, tm_ref, state = ref
        _settle(out, _continued(build, net, res, None, state, tm_ref, probes), tm_ref, probes, backend, jobs, options)
    return out


def _continued(build, main, res, hand, state, tm_ref, probes):
    """The long-S1/S2 reference of the read ``main`` (its result ``res``): ``build(handoff=...)``
    makes its deck (``tm_ref``: its timings); ``hand``: the hand-over both start from. Up to the
    instant ``t`` the two decks part (``settling.parting``) it is ``main``, so it is simulated from
    ``t`` on (its sources shifted by ``-t``), from ``res``'s values at ``t`` of the nodes ``state``
    (every node that holds charge: the column's hand-over nodes and the row's pixels), given as
    initial conditions (held through the operating point, free from then on), up to its last
    reset-level sample. (deck, ``t``): its time 0 is ``t`` of the frame."""
    from .settling import parting, shifted
    t = parting(main, build(handoff=hand))
    stop = max(tm_ref[key[0]].t_reset_level(row) + tm_ref[key[0]].edge for key, _, _, row, _ in probes)
    net = shifted(build(handoff=None), t, stop)
    return _saved(replace(net, ic=tuple((m, float(res.at(f"v({m})", t))) for m in state)), probes), t


def _settle(out, ref, tm_ref, probes, backend, jobs, options):
    """Run the long-S1/S2 reference ``ref`` = (deck, the frame's time of its time 0; see
    :func:`_continued`; ``tm_ref``: its timings) and put each probe's settling error
    (double-sampled signal - the settled one) into ``out``. A reference that fails leaves its
    cells not measured (a note), not a failed frame."""
    from ..spice.result import Result
    from .settling import settled_level
    net, t0 = ref
    try:
        res = _run_one(net, backend, jobs, options, True)
    except SimulationError as exc:
        out["notes"].append(f"reference read {net.title} failed, its cells not measured: {exc.message[:200]}")
        return
    res = Result(res.time + t0, res.vectors, res.meta)
    out["decks"] += 1
    why = _retried(res)
    out["retried"] += [{"deck": net.title, "message": why}] if why else []
    for key, node, timing, row, _ in probes:
        sig, sig_ok = settled_level(res, node, tm_ref[key[0]], timing, row)
        rst, rst_ok = settled_level(res, node, tm_ref[key[0]], timing, row, which="reset")
        signal, reset_level = out["values"][key][:2]
        # error of the double-sampled signal (reset level - signal level) against the settled one
        nan = float("nan")
        out["settling"][key] = signal - (rst - sig) if sig_ok and rst_ok else nan
        out.setdefault("parts", {})[key] = ((reset_level - signal) - sig if sig_ok else nan,
                                           reset_level - rst if rst_ok else nan)
        if not (sig_ok and rst_ok):
            out["notes"].append(f"{key[0]} row {row} column {key[2]}: the long-S1 reference itself has not settled")


def _chain(task):
    """Simulate a column chain: row 0, then each row from the state the previous row's deck
    left at the row's start (see the module docstring). A failed deck ends the chain: its
    later rows are listed as failed too (they have no state to start from)."""
    design, ip, is_, tile, t_exp, with_afe, seed, max_step, backend, options, rows, title, settle, comp = task
    from .settling import pixel_nodes, reference_timings
    tm = frame_timings(design, t_exp, rows)
    kind = tile.kinds[0]
    tm_ref = reference_timings(tm, kind) if settle else None
    nodes = [m for j in tile.columns(kind, design.secondary_per_pixel)
             for m in state_nodes(design, kind, j, with_afe, rows > 1)]
    lines = [f"col_{PREFIX[kind]}_{j}" for j in tile.columns(kind, design.secondary_per_pixel)]
    t_rise = tm[kind].rs(0)[0][0]  # the first row's RS closes: the lines leave rest
    out = {"failures": [], "retried": [], "values": {}, "decks": 0, "settling": {}, "notes": []}
    hand, rest = None, {}
    for r in range(rows):
        t = replace(tile, rows=(r,))
        probes = _probes(design, t, tm, with_afe)
        hand_r = hand
        state = nodes + (pixel_nodes(kind, r, t.columns(kind, design.secondary_per_pixel)) if settle else [])
        net = _saved(array_bench(design, ip, is_, t, t_exp, with_afe, seed, max_step, title=f"{title}_r{r}",
                                 handoff=hand, compression=comp), probes, state)
        try:
            res = _run_one(net, backend, 1, options, settle)
            out["decks"] += 1
            out["values"].update(_read(res, probes))
            if r == 0:
                rest = {c: float(res.at(f"v({c})", t_rise)) for c in lines}
            if r + 1 < rows:
                t_h = tm[kind].row(r + 1)
                hand = Handoff(t_h, tuple((m, _held(m, float(res.at(f"v({m})", t_h)), rest, t_rise,
                                                    tm[kind].edge)) for m in nodes))
        except (SimulationError, KeyError, ConfigError) as exc:
            why = exc.message if isinstance(exc, SimulationError) else f"hand-over failed: {exc}"
            out["failures"].append({"deck": net.title, "message": why})
            out["failures"] += [{"deck": f"{title}_r{q}", "message": f"not simulated: row {r} of its chain failed"}
                                for q in range(r + 1, rows)]
            return out
        why = _retried(res)
        if why:
            out["retried"].append({"deck": net.title, "message": why})
        if settle:
            build = partial(array_bench, design, ip, is_, t, t_exp, with_afe, seed, max_step,
                            title=f"{title}_r{r}_long_s1", tm=tm_ref, compression=comp)
            _settle(out, _continued(build, net, res, hand_r, state, tm_ref, probes), tm_ref, probes, backend, 1,
                    options)
    return out


def _held(node: str, v: float, rest: dict, t_rise: float, edge: float):
    """What a handed-over node is held at: its value at the hand-over; a column line follows
    the line's history instead (at rest, pulled down by its load, until the first row
    selects it, then at the hand-over value), because the next row's pixel, though not
    selected, sees the line through its RS switch: the switch's leakage sets where the
    pixel's source-follower output rests, whose charge then reaches FD when RS closes
    (a line held at the hand-over value from t = 0 moved that output by 31 mV and a
    dim pixel's signal by 2 mV)."""
    if node not in rest:
        return v
    return ((0.0, rest[node]), (t_rise, rest[node]), (t_rise + edge, v))


def _task_title(task) -> str:
    """What a frame task simulates (the progress line): its chain's or its deck's title."""
    return task[0].title if len(task) == 6 else task[11]   # a tile's (net, ...) or a chain's (design, ...)


def default_split(with_afe: bool, seeded: bool = False) -> str:
    """``none`` for a Monte Carlo frame (one deck draws every device once, so a column's
    circuits are the same chip for all its rows); else ``columns`` with the AFE (its
    row-to-row memory is handed over, not re-simulated), ``rows`` without (fewer decks)."""
    return "none" if seeded else "columns" if with_afe else "rows"


def simulate_frame(design, iph_p, iph_s, with_afe: bool = False, split: str | None = None,
                   t_exp: float | None = None, mismatch_seed: int | None = None, backend: str = "batch",
                   jobs: int | None = None, scheduler=None, options=None, max_step: float | None = None,
                   kinds=KINDS, settling: bool = False, compression: dict | None = None,
                   reuse: bool = True, interpolate: bool = True) -> Frame:
    """Simulate one frame; see the module docstring for ``split``. ``options``: simulator
    options over the kit's defaults (``spice.options``); ``kinds``: the arrays to simulate
    (the others' results stay NaN); ``settling``: also read every row with a long S1 and
    measure each subpixel's settling error (``chip.settling``; twice the decks; not for
    ``split="none"``, whose decks hold every row); ``compression``: per array t_int / t_exp of
    the currents (``scene.Photocurrents.compression``): the light falls back to the real one when
    the exposure ends (``circuits.array.array_bench``); ``reuse``: a column chain identical to an
    earlier one takes its values instead of being simulated (module docstring); ``interpolate``: the
    chains of an array whose columns each see one current in every row are interpolated in photocurrent
    from a few simulated ones, checked against held-out chains simulated too (``chip.interp``)."""
    rows, cols = frame_shape(design, iph_p, iph_s)
    n = design.secondary_per_pixel
    split = default_split(with_afe, mismatch_seed is not None) if split is None else split
    if mismatch_seed is not None and split != "none":
        raise ConfigError("", "split", split, "none with a Monte Carlo seed (a split frame would draw a "
                          "column's devices again in every deck)")
    t_exp = design.experiment.t_window if t_exp is None else t_exp
    tm = frame_timings(design, t_exp, rows)
    if max_step is None:
        max_step = min(t.t_row for t in tm.values()) / STEPS_PER_ROW
    tasks, copies = [], []
    for tile in tiles(rows, cols, split, with_afe, kinds):
        tag = "_".join(PREFIX[k] for k in tile.kinds)
        if split == "columns":
            task = (design, iph_p, iph_s, tile, t_exp, with_afe, mismatch_seed, max_step, backend, options,
                    rows, f"frame_{rows}x{cols}_{tag}_c{tile.cols[0]}", settling, compression)
            same = _same_chain(task, tasks) if reuse and mismatch_seed is None else None
            if same is not None:
                copies.append((same, task))
            else:
                tasks.append(task)
            continue
        tag += f"_r{tile.rows[0]}" if len(tile.rows) == 1 else ""
        probes = _probes(design, tile, tm, with_afe)
        ref = None
        if settling and split == "rows":
            from .settling import pixel_nodes, reference_timings
            kind, columns = tile.kinds[0], tile.columns(tile.kinds[0], n)
            tm_ref = reference_timings(tm, kind)
            state = [m for j in columns for m in state_nodes(design, kind, j, with_afe, rows > 1)]
            ref = (partial(array_bench, design, iph_p, iph_s, tile, t_exp, with_afe, mismatch_seed, max_step,
                           title=f"frame_{rows}x{cols}_{tag}_long_s1", tm=tm_ref, compression=compression),
                   tm_ref, state + pixel_nodes(kind, tile.rows[0], columns))
        net = _saved(array_bench(design, iph_p, iph_s, tile, t_exp, with_afe, mismatch_seed, max_step,
                                 title=f"frame_{rows}x{cols}_{tag}", compression=compression), probes,
                     ref[2] if ref else ())
        tasks.append((net, backend, 1 if scheduler is not None else jobs, options, probes, ref))
    shape = {"primary": (rows, cols), "secondary": (rows, n * cols)}
    sig = {k: np.full(shape[k], np.nan) for k in KINDS}
    rst = {k: np.full(shape[k], np.nan) for k in KINDS}
    afe = {k: np.full(shape[k], np.nan) for k in KINDS} if with_afe else {}
    failures, retried, decks = [], [], 0
    settle = {k: np.full(shape[k], np.nan) for k in KINDS if k in kinds} if settling else {}
    parts = {k: np.full((*shape[k], 2), np.nan) for k in settle}
    notes = [] if split != "none" else ["not measured: a frame with split='none' reads every row in one deck"]
    t0 = time.perf_counter()
    fn, desc = (_chain, "frame column chains") if split == "columns" else (_probe, "frame tiles")

    def run(ts):
        return dict(run_tasks(fn, ts, jobs=jobs, scheduler=scheduler, desc=desc, label=_task_title))
    if interpolate and split == "columns" and mismatch_seed is None:
        outs, anchors, interpolated = _interpolated(tasks, run, design, kinds, t_exp)
    else:
        outs, anchors, interpolated = run(tasks), [], []
    outs = [*outs.values(), *anchors,
            *(_copied(outs[src], tasks[src], task, n) for src, task in copies if src in outs)]
    for out in outs:
        failures += out["failures"]
        retried += out["retried"]
        decks += out["decks"]
        for (k, r, j), (s, lv, a) in out["values"].items():
            sig[k][r, j], rst[k][r, j] = s, lv
            if with_afe:
                afe[k][r, j] = a
        for (k, r, j), e in out.get("settling", {}).items():
            settle[k][r, j] = e
        for (k, r, j), e in out.get("parts", {}).items():
            parts[k][r, j] = e
        notes += out.get("notes", [])
    return Frame(rows, cols, sig, rst, afe, decks, time.perf_counter() - t0, split, failures, retried,
                 settle, notes if settling else [], parts,
                 [{"chain": task[11], "from": tasks[src][11]} for src, task in copies], interpolated)


def _interpolated(tasks, run, design, kinds, t_exp) -> tuple[dict, list, list]:
    """Run the chains ``tasks`` (``run``: {index: out}), those of an array that ``chip.interp`` can
    interpolate in photocurrent through its anchors, checked on held-out chains (else simulated after
    all): ({index: out} of every task, the outs of runs whose cells are no subpixel's - the anchors, an
    array's converged runs when its check refused them - with their decks and retries only: a failure
    there is said in ``Frame.interpolated`` and the array simulated whole, ``Frame.interpolated``)."""
    from . import interp
    plans = interp.plan(tasks, kinds, design, t_exp, lambda t, mine, to: renamed(_first_deck(t), mine, to), CONVERGED)
    rest = {i for p in plans.values() for i in p["rest"]}
    first = [i for i in range(len(tasks)) if i not in rest]
    anchors = [a for p in plans.values() for a in p["anchors"]]
    tight = {i: t for p in plans.values() for i, t in p["tight"].items()}
    got = run([tight.get(i, tasks[i]) for i in first] + anchors)
    outs = {i: got[m] for m, i in enumerate(first)}
    anchor_outs, records, later = [got[len(first) + m] for m in range(len(anchors))], [], []
    start = 0
    for kind, p in plans.items():
        mine, start = anchor_outs[start:start + len(p["anchors"])], start + len(p["anchors"])
        done, rec = interp.resolve(p, kind, outs, mine)
        rec["held_out_chains"] = [tasks[i][11] for i in p["held_out"]]
        records.append(rec)
        if done is None:   # the array as the exhaustive path gives it, at the kit's tolerances
            later += [*p["rest"], *p["tight"]]
        else:
            outs.update(done)
            rec["columns"] = sorted(int(j) for i in p["rest"] for j in p["cols"][i])
    spent = list(anchor_outs)
    if later:
        spent += [outs[i] for i in later if i in outs]
        got = run([tasks[i] for i in later])
        outs.update({i: got[m] for m, i in enumerate(later)})
    return outs, [{"decks": o["decks"], "retried": o["retried"], "failures": [], "values": {}} for o in spent], records


def _same_chain(task, earlier) -> int | None:
    """The index in ``earlier`` of a column chain identical to ``task``'s (module docstring: same
    array and column count, the same photocurrents in every row bit for bit, and the first row's
    deck the same once its column numbers are renamed), or None."""
    design, tile = task[0], task[3]
    n = design.secondary_per_pixel
    kind = tile.kinds[0]
    pick = 1 if kind == "primary" else 2
    mine = tile.columns(kind, n)
    for i, other in enumerate(earlier):
        t2 = other[3]
        theirs = t2.columns(kind, n)
        if t2.kinds != tile.kinds or len(theirs) != len(mine) or any(a % n != b % n for a, b in zip(mine, theirs)):
            continue
        if not np.array_equal(np.asarray(task[pick])[:, mine], np.asarray(other[pick])[:, theirs]):
            continue
        try:
            a, b = (_first_deck(x) for x in (other, task))
        except (ConfigError, ValueError, KeyError):   # the chain says it when it runs (a failure of its own)
            return None
        if a == renamed(b, mine, theirs):
            return i
    return None


def renamed(text: str, mine, to) -> str:
    """A deck's text with its column numbers ``mine`` renamed to ``to`` (in node and element names)."""
    import re
    names = dict(zip(map(str, mine), map(str, to)))
    return re.sub(r"(?<=_)(\d+)(?![\d.eE])", lambda m: names.get(m.group(1), m.group(1)), text)


def _first_deck(task) -> str:
    """The text of a chain's first deck, its title left out (what ngspice simulates)."""
    design, ip, is_, tile, t_exp, with_afe, seed, max_step, _b, _o, _rows, _title, _s, comp = task
    net = array_bench(design, ip, is_, replace(tile, rows=(0,)), t_exp, with_afe, seed, max_step, title="chain",
                      compression=comp)
    return net.text()


def _copied(out: dict, source, task, n: int) -> dict:
    """The results of chain ``source`` as those of the identical chain ``task``: each cell moved to
    the same place among ``task``'s columns; a failure of the source is the copy's too."""
    kind = task[3].kinds[0]
    to = dict(zip(source[3].columns(kind, n), task[3].columns(kind, n)))
    moved = {part: {(k, r, to[j]): v for (k, r, j), v in out.get(part, {}).items()}
             for part in ("values", "settling", "parts")}
    import re

    def said(what: str, entries: list) -> list:
        return [{"deck": f["deck"].replace(source[11], task[11], 1),
                 "message": f"identical to chain {source[11]}, whose deck {what}: {f['message']}"} for f in entries]
    notes = [re.sub(r"column (\d+):", lambda m: f"column {to.get(int(m.group(1)), m.group(1))}:", x)
             for x in out.get("notes", [])]
    return {**moved, "failures": said("failed", out["failures"]), "retried": said("was retried", out["retried"]),
            "decks": 0, "notes": notes}


#: Tolerances at which a split is judged against the undivided deck: at the defaults two decks
#: with different step sequences already scatter by 0.2 - 0.4 mV (docs/arrays.md), which would hide
#: what the split itself changes; at reltol 1e-6, abstol 1e-12 the undivided deck moves by
#: < 0.08 mV with trtol or the maximum step (abstol 1e-14 stops ngspice there).
CONVERGED = (("reltol", 1e-6), ("abstol", 1e-12))


def check_split(design, iph_p, iph_s, split: str | None = None, limit: float = 1e-4, **kw) -> dict:
    """The split frame against the undivided deck of each array (``split="none"``), both at
    ``CONVERGED`` tolerances: largest differences (V) of the signal, reset level and AFE
    output, and ``void``: decks that failed or were retried (at looser options), and cells
    without a value; ``ok`` when nothing is void and every difference is within ``limit``."""
    kw = dict(kw, options=CONVERGED, interpolate=False)
    f = simulate_frame(design, iph_p, iph_s, split=split, **kw)
    ref = simulate_frame(design, iph_p, iph_s, split="none", **kw)
    kinds = kw.get("kinds", KINDS)
    out = {"split": f.split, "wall_s": f.wall_s + ref.wall_s, "limit_V": limit,
           "void": [e["deck"] for r in (f, ref) for e in r.failures + r.retried]}
    for name in ("signal", "reset_level", "afe"):
        a, b = getattr(f, name), getattr(ref, name)
        if not a:
            continue
        d = np.concatenate([np.abs(a[k] - b[k]).ravel() for k in kinds])
        if np.isnan(d).any():
            out["void"].append(f"{int(np.isnan(d).sum())} {name} cells without a value")
        out[f"max_diff_{name}_V"] = float(np.nanmax(d)) if np.isfinite(d).any() else None
    diffs = [v for k, v in out.items() if k.startswith("max_diff")]
    out["ok"] = not out["void"] and all(v is not None and v <= limit for v in diffs)
    return out
