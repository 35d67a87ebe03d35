"""The benchmark suite: every figure a ratio or a scaling measured in this run.

    python3 benchmarks/run.py [--json] [--quick] [--skip NAME ...]

Figures (run on a quiet machine: the wall times scale with the load, the ratios much less):

- ``overhead_vs_raw``: the kit's batch backend (deck writing, scratch folder, model
  links, raw read, result typing, cache key) over raw ``ngspice -b -r`` on the same
  decks as the kit hands them to ngspice (6 dual-pixel benches with their AFEs, serial,
  uncached, each deck's fastest of 5 runs of each kind). Limit 1.05.
  ``kit_vs_raw_lib``: the kit over raw ngspice on the decks as written, reading the
  model library through ``.lib`` (below 1: the flattened sections save more than the
  kit costs; the one-off flattening, ~40 ms per process, is outside the timing).
  ``kit_outside_ngspice``: the share of the kit runs' time spent outside their own ngspice
  process (deck, links, raw read, result), measured within each run, so not subject to
  the load drifting between runs that limits the two ratios above (+-4 % here).
- ``flattened_vs_lib``: raw ngspice on short decks (dual-pixel bench without AFE) with
  the model sections flattened over the same decks reading the library through ``.lib``
  (fastest of 5 each), with ``flattened_deck_s`` / ``lib_deck_s``.
- ``parallel_speedup``: a 16-point sweep (``run_sweep``, dual-pixel bench with its AFEs,
  ~1 s a point) on 1 worker over the same on every core (2 here), each from an empty
  cache. Limit 1.9 on 2 cores.
- array frames (``simulate_frame``, both arrays, column loads): 2 x 2, 4 x 4, 8 x 8 without
  the AFE (one deck per array and row), ``scaling_exponent`` k of t ~ pixels^k over them;
  one full 27-row primary column with its S1X/S2X and AFE (``column_afe_s``, limit 60 s)
  and the whole chip, 27 x 50 dual pixels with every column's load, samplers and AFE
  (``whole_array_s``, limit 900 s; both skipped by ``--quick``, which also leaves out the 8 x 8
  frame and runs each step on the fewest decks that give its figure), both as column chains (one
  deck per row and group of columns, the column state handed over), each with
  ``*_decks`` and ``*_per_deck_s`` (wall time x busy workers / decks).
- ``analytic_points_per_s``: the analytic C(V) discharge model's evaluations per second.
- ``sizing_solve_s`` / ``sizing_vs_spice``: the casadi sizing solve against one SPICE run.
- ``gap_cold_cli_s``: ``pixelkit gap diagnose`` of one measured CSV in a fresh process with an
  empty cache (limit 10 s); ``gap_diagnosis_s`` / ``gap_vs_spice``: the diagnosis of 2000 rows
  against one SPICE experiment run (``benchmarks/gap.py``).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from common import reference_design


def _fresh_cache():
    os.environ["PIXELKIT_CACHE"] = tempfile.mkdtemp(prefix="pk-bench-")


def _write_decks(nets, tmp: str) -> None:
    """Each deck in ``tmp`` as written (``l{k}.cir``, ngspice reads the library through
    ``.lib``) and as the kit hands it to ngspice (``d{k}.cir``, sections flattened), with
    the kit's ``.spiceinit`` and model links."""
    from pixelkit.spice import flatlib, scratch
    from pixelkit.spice.engine import _prepare
    Path(tmp, ".spiceinit").write_text(scratch.SPICEINIT)
    for k, net in enumerate(nets):
        text, links = _prepare(net, None).text(), net.model_links()
        flat, flat_links = flatlib.run_deck(text, links, net.includes, scratch.root())
        if flat == text:
            raise SystemExit("benchmark: the model library was not flattened; flattened and .lib runs would agree")
        Path(tmp, f"l{k}.cir").write_text(text)
        Path(tmp, f"d{k}.cir").write_text(flat)
    for name, folder in flat_links.items():
        Path(tmp, name).symlink_to(folder)


def _ngspice(tmp: str, deck: str, out: str) -> float:
    t0 = time.perf_counter()
    subprocess.run(["ngspice", "-b", "-r", out, deck], cwd=tmp, capture_output=True, check=True)
    return time.perf_counter() - t0


def _fastest(runs: list, k: int, repeats: int) -> list[float]:
    """Each run's fastest of ``repeats`` (a load spike only slows a run down), the order
    rotating with ``k`` and the repeat, so that no kind of run always goes first."""
    times = [[] for _ in runs]
    for r in range(repeats):
        for j in range(len(runs)):
            i = (j + k + r) % len(runs)
            times[i].append(runs[i]())
    return [min(t) for t in times]


def overhead_vs_raw(d, n: int = 6, repeats: int = 5) -> dict:
    """Raw and kit runs interleaved deck by deck, so a change of machine load hits both alike;
    each deck's fastest of ``repeats`` runs of each kind.

    ``overhead_vs_raw`` runs raw ngspice on the decks exactly as the kit hands them over
    (model sections flattened, ``spice/flatlib.py``); ``kit_vs_raw_lib`` runs it on the
    decks as written, where ngspice reads the model library itself (what a user's own
    script does): the kit's gain from the flattening, net of its overhead.
    """
    from pixelkit.circuits.testbench import dual_pixel_bench
    from pixelkit.spice import simulate
    nets = [dual_pixel_bench(d, 1e-10 * (k + 1), 5e-12 * (k + 1), with_afe=True, title=f"ovh{k}") for k in range(n)]
    raw = raw_lib = kit = 0.0
    with tempfile.TemporaryDirectory() as tmp:
        _write_decks(nets, tmp)
        simulate(nets[0], use_cache=False)  # imports and first-use set-up outside the timing

        inside = []  # (kit wall, its ngspice process's wall) of every kit run

        def kit_run(net):
            t0 = time.perf_counter()
            res = simulate(net, use_cache=False)
            inside.append((time.perf_counter() - t0, res.meta["wall_s"]))
            return inside[-1][0]
        for k, net in enumerate(nets):
            a, b, c = _fastest([lambda: _ngspice(tmp, f"d{k}.cir", f"o{k}.raw"),
                                lambda: _ngspice(tmp, f"l{k}.cir", f"p{k}.raw"), lambda: kit_run(net)], k, repeats)
            raw, raw_lib, kit = raw + a, raw_lib + b, kit + c
    total, spice = np.sum(inside, axis=0)
    return {"overhead_vs_raw": kit / raw, "kit_vs_raw_lib": kit / raw_lib, "kit_outside_ngspice": total / spice - 1,
            "raw_s": raw, "raw_lib_s": raw_lib, "kit_s": kit, "decks": n, "repeats": repeats}


def flattened_vs_lib(d, n: int = 4, repeats: int = 5) -> dict:
    """Raw ngspice on short decks (the dual-pixel bench without its AFE, ~0.2 s) as the kit
    hands them over (model sections flattened) over the same decks reading the library
    through ``.lib``: what the flattening saves where start-up weighs most."""
    from pixelkit.circuits.testbench import dual_pixel_bench
    nets = [dual_pixel_bench(d, 1e-10 * (k + 1), 5e-12 * (k + 1), title=f"flat{k}") for k in range(n)]
    flat = lib = 0.0
    with tempfile.TemporaryDirectory() as tmp:
        _write_decks(nets, tmp)
        for k in range(n):
            a, b = _fastest([lambda: _ngspice(tmp, f"d{k}.cir", f"o{k}.raw"),
                             lambda: _ngspice(tmp, f"l{k}.cir", f"p{k}.raw")], k, repeats)
            flat, lib = flat + a, lib + b
    return {"flattened_vs_lib": flat / lib, "flattened_deck_s": flat / n, "lib_deck_s": lib / n}


def parallel_speedup(d, points: int = 16) -> dict:
    from pixelkit.spice.engine import default_jobs
    from pixelkit.sweep.run import run_sweep
    from pixelkit.sweep.space import parse_axis
    axes = [parse_axis(f"iph_p=lin:100p:1.6n:{points}")]
    out = {}
    for jobs in (1, default_jobs()):
        _fresh_cache()
        t0 = time.perf_counter()
        s = run_sweep(d, axes, with_afe=True, jobs=jobs)
        out[jobs] = time.perf_counter() - t0
        assert not s.failures
    j = default_jobs()
    return {"parallel_speedup": out[1] / out[j], "serial_s": out[1], "parallel_s": out[j], "workers": j,
            "points": points}


def _frame(d, rows, cols, with_afe=False, kinds=("primary", "secondary")):
    from pixelkit.chip.frame import simulate_frame
    from pixelkit.chip.scene import default_map, photocurrents
    from pixelkit.spice.engine import default_jobs
    m, unit = default_map(rows, d.secondary_per_pixel * cols)
    ph = photocurrents(d, rows, cols, m, unit)
    _fresh_cache()
    f = simulate_frame(d, ph.iph_p, ph.iph_s, with_afe=with_afe, kinds=kinds)
    assert not f.failures, f.failures
    tasks = f.decks // rows if f.split == "columns" else f.decks  # chains run their rows in turn
    return f.wall_s, f.decks, f.wall_s * min(default_jobs(), tasks) / f.decks


def array_scaling(d, quick: bool) -> dict:
    sizes = [(2, 2), (4, 4)] if quick else [(2, 2), (4, 4), (8, 8)]
    times = {f"{r}x{c}": _frame(d, r, c)[0] for r, c in sizes}
    px = np.array([r * c for r, c in sizes], float)
    k = float(np.polyfit(np.log(px), np.log(list(times.values())), 1)[0])
    out = {"frame_s": times, "scaling_exponent": k}
    runs = {} if quick else {"column_afe": (27, 1, ("primary",)), "whole_array": (27, 50, ("primary", "secondary"))}
    for name, (rows, cols, kinds) in runs.items():
        out[f"{name}_s"], out[f"{name}_decks"], out[f"{name}_per_deck_s"] = _frame(d, rows, cols, True, kinds)
    return out


def analytic_points_per_s(d) -> dict:
    from pixelkit.physics.discharge import voltage
    from pixelkit.physics.subpixel import pd_node
    node = pd_node(d, "primary", parasitics=True)
    t = np.linspace(0, d.experiment.t_window, 10000)
    currents = np.geomspace(1e-12, 3e-9, 100)
    t0 = time.perf_counter()
    for i in currents:
        voltage(t, node, d.pixel.v_pd_reset, i)
    dt = time.perf_counter() - t0
    return {"analytic_points_per_s": t.size * currents.size / dt}


def sizing(d, repeats: int = 5) -> dict:
    import sizing as sizing_bench
    r = sizing_bench.measure(d, repeats=repeats)
    return {"sizing_solve_s": r["solve_s"], "sizing_vs_spice": r["solve_s"] / r["spice_s"]}


def gap(_d, rows: int = 2000) -> dict:
    """On the thesis's read ([Thesis2019]): the diagnosis needs a surrogate, and that design ships one (the
    reference design's is built from SPICE by its first ``gap predict``, which
    ``benchmarks/main_job.py`` times)."""
    import gap as gap_bench
    from common import THESIS_READ
    from pixelkit.design import load_design
    r = gap_bench.measure(load_design(THESIS_READ), rows=rows)
    return {"gap_cold_cli_s": r["cold_cli_s"], "gap_diagnosis_s": r["diagnosis_s"],
            "gap_vs_spice": r["diagnosis_s"] / r["spice_s"]}


STEPS = {"overhead": overhead_vs_raw, "flatlib": flattened_vs_lib, "parallel": parallel_speedup, "arrays": None,
         "analytic": analytic_points_per_s, "sizing": sizing, "gap": gap}
#: The quick profile (``--quick``, what tests/test_benchmarks.py runs): every step, each on the
#: fewest decks that still give its figure (the whole chip and the 27-row column left out).
QUICK = {"overhead": dict(n=2, repeats=2), "flatlib": dict(n=2, repeats=2), "parallel": dict(points=4),
         "sizing": dict(repeats=1), "gap": dict(rows=200)}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--quick", action="store_true", help="the quick profile: fewest decks per figure, no whole "
                                                         "27 x 50 array nor 27-row column (QUICK)")
    ap.add_argument("--skip", nargs="*", default=[], choices=list(STEPS))
    a = ap.parse_args(argv)
    d = reference_design()
    res = {"cores": os.cpu_count(), "load_before": os.getloadavg()[0]}
    for name, fn in STEPS.items():
        if name in a.skip:
            continue
        res.update(array_scaling(d, a.quick) if name == "arrays" else fn(d, **(QUICK.get(name, {}) if a.quick else {})))
    res["load_after"] = os.getloadavg()[0]
    if a.json:
        print(json.dumps(res, indent=1))
        return
    for k, v in res.items():
        if isinstance(v, dict):
            print(f"{k}: " + ", ".join(f"{kk} {vv:.2f}" for kk, vv in v.items()))
        else:
            print(f"{k}: {v:.4g}" if isinstance(v, float) else f"{k}: {v}")


if __name__ == "__main__":
    main(sys.argv[1:])
