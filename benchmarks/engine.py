"""Engine performance, as ratios against a baseline measured in the same run.

    python benchmarks/engine.py [N]

Baseline: raw `ngspice -b -r` on the dual-pixel bench deck, N times in series.
Compared: the kit's batch backend (same decks, raw read + result typing),
the shared-library backend, 2 parallel workers of each, and cache hits.
"""
from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import reference_design
from pixelkit.circuits.testbench import dual_pixel_bench
from pixelkit.spice import simulate_many
from pixelkit.spice.engine import _prepare


def main(n: int = 16):
    d = reference_design()
    nets = [dual_pixel_bench(d, 1e-10 * (k + 1), 5e-12 * (k + 1), title=f"bench{k}") for k in range(n)]
    with tempfile.TemporaryDirectory() as tmp:
        Path(tmp, ".spiceinit").write_text("set num_threads=1\n")
        for k, net in enumerate(nets):
            Path(tmp, f"d{k}.cir").write_text(_prepare(net, None).text())
        t0 = time.perf_counter()
        for k in range(n):
            subprocess.run(["ngspice", "-b", "-r", f"o{k}.raw", f"d{k}.cir"], cwd=tmp, capture_output=True, check=True)
        base = time.perf_counter() - t0
    rows = [("raw ngspice -b -r, serial (baseline)", base)]
    for backend in ("batch", "shared"):
        for jobs in (1, 2):
            t0 = time.perf_counter()
            simulate_many(nets, backend=backend, jobs=jobs, use_cache=False)
            rows.append((f"pixelkit {backend}, {jobs} worker(s)", time.perf_counter() - t0))
    simulate_many(nets, backend="batch", jobs=2)
    t0 = time.perf_counter()
    simulate_many(nets, backend="batch", jobs=2)
    rows.append(("pixelkit cache hits", time.perf_counter() - t0))
    print(f"{n} dual-pixel bench decks ({os.cpu_count()} cores)")
    for label, t in rows:
        print(f"  {label:<40} {t:7.3f} s   {t / base:6.2f} x baseline")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 16)
