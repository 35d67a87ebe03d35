"""Layout sign-off time: the dual pixel with its column circuits through the foundry's DRC deck and
the kit's LVS (target: DRC + LVS < 30 s on 2 cores).

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


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "designs" / "dual_pixel_gf180.toml")
