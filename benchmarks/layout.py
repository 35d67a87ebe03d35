"""Layout sign-off time: the dual pixel with its column circuits through the foundry's DRC deck and
the kit's LVS (target: DRC + LVS < 30 s on 2 cores); ``pixelkit signoff`` (every check: DRC, the
foundry's LVS where its deck is installed, the kit's LVS, extraction, light map) on the same cell
against that (target: within 1.5 x of generation + DRC + LVS, what ``layout --drc --lvs`` does for the
cell) and on the 2 x 2 chip with its AFEs (target: 60 s).

Measured in the same run, as the baseline: the same deck on an empty cell (its fixed cost: it
executes every one of its rules whatever the layout
holds). Printed: generation, DRC (deep mode, 2 threads), LVS, their sum against the target, the
ratio of the DRC to the deck's empty-cell run, the CPU time of the DRC process (what it costs on
free cores: the wall time under load is that much longer), and the machine's load (the 2 cores
are shared).

    python3 benchmarks/layout.py [designs/dual_pixel_gf180.toml]
"""
from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

from common import ROOT, child_cpu_s, empty_gds

from pixelkit.design import load_design
from pixelkit.layout.flow import SIGNOFF_TOP, write_gds
from pixelkit.layout.library import build_cells, to_library
from pixelkit.layout.signoff.drc import run_drc
from pixelkit.layout.signoff.lvs import run_lvs

TARGET_S = 30.0


def main(design_file: Path) -> None:
    d = load_design(design_file)
    work = Path(tempfile.mkdtemp(prefix="pk-layout-bench-"))
    load0 = os.getloadavg()[0]
    cpu0 = _cpu()
    t0 = time.perf_counter()
    cells = build_cells(d)
    gds = write_gds(to_library(d, cells), work / "x.gds")
    gen = time.perf_counter() - t0
    c0 = child_cpu_s()
    base = run_drc(empty_gds(work / "empty.gds", d), "EMPTY", d.tech, work / "base")
    c1 = child_cpu_s()
    drc = run_drc(gds, SIGNOFF_TOP, d.tech, work / "drc")
    c2 = child_cpu_s()
    lvs = run_lvs(gds, SIGNOFF_TOP, d)
    base_cpu = _cpu() - cpu0 - (c1 - c0)       # generation, the cell's DRC and LVS (not the empty-cell DRC)
    total = drc.seconds + lvs.seconds
    print(f"design {d.name} ({d.tech.name}), cell {SIGNOFF_TOP}; {drc.klayout}; load average {load0:.2f} "
          f"-> {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    print(f"  generation (all cells, GDS)          {gen:6.2f} s")
    print(f"  DRC, foundry deck, deep, 2 threads     {drc.seconds:6.2f} s  ({'clean' if drc.clean else drc.by_rule()})")
    print(f"  DRC of an empty cell (deck overhead)   {base.seconds:6.2f} s")
    print(f"  CPU time of the DRC run (klayout and its children, user + system): {c2 - c1:.2f} s; of the "
          f"empty-cell run {c1 - c0:.2f} s (what a run costs when the cores are free)")
    print(f"  LVS, kit extraction                    {lvs.seconds:6.2f} s  ({'match' if lvs.match else 'MISMATCH'})")
    print(f"  DRC + LVS                              {total:6.2f} s  (target < {TARGET_S:g} s: "
          f"{'met' if total < TARGET_S else 'NOT met'})")
    print(f"  ratio DRC / empty-cell DRC             {drc.seconds / base.seconds:6.2f}")
    print(f"  layout --drc --lvs on {SIGNOFF_TOP} (generation + DRC + LVS): {gen + total:6.2f} s wall, {base_cpu:6.2f} s CPU")
    signoff_timing(d, work, gen + total, base_cpu)


def _cpu() -> float:
    import resource
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime + child_cpu_s()


def signoff_timing(d, work: Path, baseline: float, baseline_cpu: float) -> None:
    """``pixelkit signoff`` (the API the command calls) on DUALPIX_COL, against ``baseline`` (generation +
    DRC + LVS of the same cell, measured in this run), and on the 2 x 2 chip with its AFEs."""
    from pixelkit.layout.anylayout import signoff
    from pixelkit.layout.flow import layout_design
    from pixelkit.layout.signoff.foundry import available
    r = layout_design(d, work / "drawn", 2, 2, pictures=False, afe=True)
    gds, spice = Path(r["gds"]), {k: Path(v) for k, v in r["spice"].items()}
    foundry = available(d.tech)
    print(f"  signoff: the fd_pv LVS deck {'installed (run)' if foundry is None else 'NOT installed (not run)'}")
    for top, target in ((SIGNOFF_TOP, None), (r["top"], 60.0)):
        c0, t0 = _cpu(), time.perf_counter()
        res = signoff(gds, spice[top], d.tech, work / f"so_{top}", top)
        wall, cpu = time.perf_counter() - t0, _cpu() - c0
        what = "; ".join(f"{k} {'ok' if res[k].get('clean', res[k].get('match', True)) else 'FAIL'}"
                         if res[k].get("run", True) else f"{k} not run" for k in
                         ("drc", "lvs", "foundry_lvs", "pex", "lightmap") if k in res)
        print(f"  signoff {top:14s}                 {wall:6.2f} s wall, {cpu:6.2f} s CPU ({what})")
        if target is None:
            print(f"  ratio signoff / layout --drc --lvs on {top}: wall {wall / baseline:5.2f} (target <= 1.5: "
                  f"{'met' if wall / baseline <= 1.5 else 'NOT met'}), CPU {cpu / baseline_cpu:5.2f}")
        else:
            print(f"  signoff of the chip with AFEs: target < {target:g} s: {'met' if wall < target else 'NOT met'}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "designs" / "dual_pixel_gf180.toml")
