"""Sizing speed: the analytic casadi solve against one SPICE run of the pixel, same process.

    python benchmarks/sizing.py [repeats]      (also a module of benchmarks/run.py)
"""
from __future__ import annotations

import statistics
import sys
import time

from common import reference_design
from pixelkit.circuits.testbench import dual_pixel_bench
from pixelkit.optimize.levels import analytic_curves
from pixelkit.optimize.sizing import solve
from pixelkit.spice import simulate


def measure(d, repeats: int = 20) -> dict:
    """Median wall time of curves + solve, of the IPOPT solve alone, and one SPICE run (s)."""
    t0 = time.perf_counter()
    simulate(dual_pixel_bench(d, 1e-9, 4e-11), use_cache=False)
    spice = time.perf_counter() - t0
    walls, solves = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        r = solve(d, analytic_curves(d))
        walls.append(time.perf_counter() - t0)
        solves.append(r["solve_time_s"])
    return {"spice_s": spice, "wall_s": statistics.median(walls), "solve_s": statistics.median(solves)}


def main(repeats: int = 20):
    r = measure(reference_design(), repeats)
    spice, w, s = r["spice_s"], r["wall_s"], r["solve_s"]
    print(f"one SPICE run of the dual-pixel bench (baseline): {spice * 1e3:8.1f} ms")
    print(f"analytic sizing, curves + casadi/IPOPT (median of {repeats}): {w * 1e3:8.1f} ms  "
          f"{w / spice:5.2f} x baseline")
    print(f"  of which the IPOPT solve:                     {s * 1e3:8.1f} ms  {s / spice:5.2f} x baseline")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 20)
