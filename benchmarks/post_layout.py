"""Post-layout cost: extraction of the whole chip and a post-layout 2 x 2 frame against the schematic one.

1. Extraction of the 27 x 50 chip of ``designs/dual_pixel_gf180.toml`` (target < 5 min; an empty cache): the
   arrays are instances of one dual pixel and one column circuit per column kind, so the kit
   extracts ``DUALPIX`` and ``DUALPIX_COL`` once (draw, LVS match, 2.5D) and scales the lines by the
   rows and columns; the dual pixel alone is the baseline (target < 10 s).
2. ``pixelkit array D --rows 2 --cols 2`` (fig. 3.13's 2 x 2), schematic and ``--post-layout``, each
   in a fresh process with an empty simulation cache (target: post-layout < 3 x schematic): the
   post-layout run once with its extraction (empty cache; without ``--afe`` the view draws and extracts
   no AFE), once with the extraction cached. Wall
   time and CPU time (the command and every process it waited for: ngspice, KLayout), the CPU
   ratio being the one a shared machine's load does not move.

    python3 benchmarks/post_layout.py
"""
from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time

from common import ROOT

from pixelkit.design import load_design
from pixelkit.layout.pex import cell_geometry
from pixelkit.layout.pex.capacitance import capacitances
from pixelkit.layout.pex.overlay import post_layout_view

GF = ROOT / "designs" / "dual_pixel_gf180.toml"


def _timed(f):
    """f(), its wall time and its CPU time (s; this process: the extraction runs no child)."""
    t0, c0 = time.perf_counter(), time.process_time()
    r = f()
    return r, time.perf_counter() - t0, time.process_time() - c0


def main():
    os.environ["PIXELKIT_CACHE"] = tempfile.mkdtemp(prefix="pk-bench-")   # the chip is extracted, not read back
    d = load_design(GF)
    _, t_pix, c_pix = _timed(lambda: capacitances(cell_geometry(d, "DUALPIX"), d.tech.stack))
    pl, t_chip, c_chip = _timed(lambda: post_layout_view(d))
    print(f"extraction: dual pixel {t_pix:.2f} s wall, {c_pix:.2f} s CPU (target < 10 s); the {d.primary.rows} x "
          f"{d.primary.cols} chip (DUALPIX + DUALPIX_COL, lines scaled, and the AFEs) {t_chip:.2f} s wall, "
          f"{c_chip:.2f} s CPU (target < 300 s)")
    for k, v in pl.post_layout.resistance.items():
        print(f"    {k}: {v:.0f} Ohm")
    print(f"    column line lumped C: primary {pl.post_layout.column_cap['primary'] * 1e15:.1f} fF, "
          f"secondary {pl.post_layout.column_cap['secondary'] * 1e15:.1f} fF")
    times, cpu = {}, {}
    for label, extra in (("schematic", []), ("post-layout, extraction included", ["--post-layout"]),
                         ("post-layout, extraction cached", ["--post-layout"])):
        if not label.endswith("cached"):
            cache = tempfile.mkdtemp(prefix="pk-bench-")
        else:   # the same cache keeps the extraction; the simulations are dropped for a cold run
            import shutil
            shutil.rmtree(os.path.join(cache, "sim"), ignore_errors=True)
        env = dict(os.environ, PIXELKIT_CACHE=cache)
        with tempfile.TemporaryDirectory() as out:
            t0 = time.perf_counter()
            c0 = resource.getrusage(resource.RUSAGE_CHILDREN)
            r = subprocess.run([sys.executable, "-m", "pixelkit", "array", str(GF), "--rows", "2", "--cols", "2",
                                "--quiet", "--out", out, *extra], env=env, capture_output=True, text=True)
            times[label] = time.perf_counter() - t0
            c1 = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu[label] = (c1.ru_utime - c0.ru_utime) + (c1.ru_stime - c0.ru_stime)
            if r.returncode:
                sys.exit(f"{label} 2 x 2 failed: {r.stderr.strip()[-400:]}")
        print(f"2 x 2 frame, {label}: {times[label]:.1f} s wall, {cpu[label]:.1f} s CPU")
    for label in ("post-layout, extraction included", "post-layout, extraction cached"):
        print(f"{label} / schematic: {times[label] / times['schematic']:.2f} wall, "
              f"{cpu[label] / cpu['schematic']:.2f} CPU (target < 3)")
    print(f"load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
