"""Readout and array sign-off time (issue 29 targets on 2 cores): DRC + LVS of the 2 x 2 array with
its AFE columns < 60 s; the design's whole chip (27 x 50 with every AFE, full shield) generated
< 2 min and through the foundry DRC deck in deep mode < 10 min.

Measured in the same run, as baselines: the deck on an empty cell (its fixed cost: it runs every
rule whatever the layout holds) and the 2 x 2 generation (the whole chip reuses its cells: what
grows with the array is the hierarchy, not the drawing). Printed beside each time: the ratio to
its baseline, the GDS sizes (by reference: the 27 x 50 file is not 337 times the 2 x 2), the CPU
time of the DRC processes (what a run costs on free cores) and the machine's load (the 2 cores are
shared: wall times under load are longer by about the load over the cores).

    python3 benchmarks/layout_readout.py [designs/dual_pixel_gf180.toml] [--skip-chip-drc]
"""
from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

from common import ROOT, child_cpu_s, empty_gds

from pixelkit.design import load_design
from pixelkit.layout.flow import write_gds
from pixelkit.layout.library import build_chip_cells, to_library
from pixelkit.layout.shield import exposed_junctions
from pixelkit.layout.signoff.drc import run_drc
from pixelkit.layout.signoff.lvs import run_lvs

TARGET_2X2_S, TARGET_GEN_S, TARGET_DRC_S = 60.0, 120.0, 600.0


def _generate(d, rows, cols, path):
    t0 = time.perf_counter()
    cells, top = build_chip_cells(d, rows, cols, afe=True, shield="full")
    gds = write_gds(to_library(d, cells), path)
    return time.perf_counter() - t0, gds, top, cells


def main(design_file: Path, chip_drc: bool) -> None:
    d = load_design(design_file)
    work = Path(tempfile.mkdtemp(prefix="pk-readout-bench-"))
    print(f"design {d.name} ({d.tech.name}); load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    c0 = child_cpu_s()
    base = run_drc(empty_gds(work / "empty.gds", d), "EMPTY", d.tech, work / "base")
    c1 = child_cpu_s()
    g2, gds2, top2, _ = _generate(d, 2, 2, work / "chip2.gds")
    drc2 = run_drc(gds2, top2, d.tech, work / "drc2")
    c2 = child_cpu_s()
    lvs2 = run_lvs(gds2, top2, d)
    s2 = drc2.seconds + lvs2.seconds
    print(f"  DRC of an empty cell (deck overhead)       {base.seconds:7.2f} s  (CPU {c1 - c0:.1f} s)")
    print(f"  {top2}: generation                  {g2:7.2f} s, GDS {gds2.stat().st_size / 1e3:.0f} kB")
    print(f"    DRC, foundry deck, deep, 2 threads       {drc2.seconds:7.2f} s  ({'clean' if drc2.clean else drc2.by_rule()}; "
          f"CPU {c2 - c1:.1f} s; {drc2.seconds / base.seconds:.2f} x the empty cell)")
    print(f"    LVS, kit extraction                      {lvs2.seconds:7.2f} s  ({'match' if lvs2.match else 'MISMATCH'})")
    print(f"    DRC + LVS                                {s2:7.2f} s  (target < {TARGET_2X2_S:g} s: "
          f"{'met' if s2 < TARGET_2X2_S else 'NOT met'})")
    rows, cols = d.primary.rows, d.primary.cols
    g, gds, top, cells = _generate(d, rows, cols, work / "chip.gds")
    print(f"  {top}: generation                {g:7.2f} s  (target < {TARGET_GEN_S:g} s: "
          f"{'met' if g < TARGET_GEN_S else 'NOT met'}; {g / g2:.2f} x the 2 x 2), GDS "
          f"{gds.stat().st_size / 1e3:.0f} kB ({gds.stat().st_size / gds2.stat().st_size:.2f} x the 2 x 2 for "
          f"{rows * cols / 4:.0f} x the pixels)")
    t0 = time.perf_counter()
    ex = exposed_junctions(gds, top, d.tech, cells[top].ports["blocks"])
    print(f"    junction left open, per block            {time.perf_counter() - t0:7.2f} s  "
          + ", ".join(f"{k} {v['exposed_m2'] * 1e12:.4g} um2" for k, v in ex.items()))
    if chip_drc:
        c3 = child_cpu_s()
        drc = run_drc(gds, top, d.tech, work / "drc")
        c4 = child_cpu_s()
        print(f"    DRC, foundry deck, deep, 2 threads       {drc.seconds:7.2f} s  (target < {TARGET_DRC_S:g} s: "
              f"{'met' if drc.seconds < TARGET_DRC_S else 'NOT met'}; {'clean' if drc.clean else drc.by_rule()}; "
              f"CPU {c4 - c3:.1f} s; {drc.seconds / base.seconds:.2f} x the empty cell)")
    print(f"  load average at the end {os.getloadavg()[0]:.2f}; work folder {work}")


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    main(Path(args[0]) if args else ROOT / "designs" / "dual_pixel_gf180.toml", "--skip-chip-drc" not in sys.argv)
