"""A frame of identical columns with every column chain simulated, and with identical chains simulated once.

    python3 benchmarks/chip_reuse.py [--rows 9] [--cols 6] [--scene uniform] [--json] [DESIGN.toml]

What ``pixelkit array DESIGN --rows R --cols C --afe --scene uniform`` simulates (column chains with
the AFE, the settling reads), twice in this process, each on a fresh empty simulation cache: first
with ``reuse=False`` (the baseline: every chain simulated, as before 2026-11-29), then with the
default ``reuse=True`` (a chain whose photocurrents equal an earlier chain's in every row takes its
values: ``chip.frame``). Printed: ngspice's CPU seconds (every child waited for), wall, decks, the
ratio of the two, and the largest difference of any subpixel's signal, reset level, AFE output and
settling error between them (the baseline simulated every one of those columns itself).
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

from common import chip_slice, frame_runs


def main(argv) -> int:
    import numpy as np

    a, d, ph = chip_slice(argv, 6, "uniform")
    runs, frames = frame_runs(d, ph, {"every chain": {"reuse": False, "interpolate": False},
                                      "reuse": {"reuse": True, "interpolate": False}}, "pk-bench-reuse-")
    for name, f in frames.items():
        runs[name]["reused_chains"] = len(f.reused)
    a0, b0 = frames["every chain"], frames["reuse"]
    diff = max(float(np.nanmax(np.abs(getattr(a0, x)[k] - getattr(b0, x)[k])))
               for x in ("signal", "reset_level", "afe", "settling") for k in ("primary", "secondary"))
    base, new = runs["every chain"], runs["reuse"]
    out = {"design": Path(a.design).name, "rows": a.rows, "cols": a.cols, "scene": a.scene, "runs": runs,
           "cpu_ratio": round(new["cpu_s"] / base["cpu_s"], 3), "wall_ratio": round(new["wall_s"] / base["wall_s"], 3),
           "max_diff_mV": round(diff * 1e3, 6)}
    if a.json:
        print(json.dumps(out, indent=1))
        return 0
    print(f"{out['design']}, {a.rows} x {a.cols} with the AFE and the settling reads, scene {a.scene}:")
    for name, r in runs.items():
        print(f"  {name:12s} {r['cpu_s']:7.1f} s CPU, {r['wall_s']:6.1f} s wall, {r['decks']} decks, "
              f"{r['reused_chains']} chains reused, load {r['load']}")
    print(f"  reuse / every chain: CPU {out['cpu_ratio']}, wall {out['wall_ratio']}; largest difference of any "
          f"figure {out['max_diff_mV']} mV")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
