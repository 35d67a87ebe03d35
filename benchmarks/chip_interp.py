"""A slice of the whole chip with every column chain simulated, and with chains interpolated in photocurrent.

    python3 benchmarks/chip_interp.py [--rows 27] [--cols 50] [--scene gradient] [--json] [DESIGN.toml]

What ``pixelkit array DESIGN --rows R --cols C --afe`` simulates (column chains with the AFE, the
settling reads, the default gradient scene), twice in this process, each on a fresh empty simulation
cache: first ``--exhaustive`` (``interpolate=False``: every chain simulated, the kit before
2026-11-29), then the default (``chip.interp``: the chains of an array whose columns each see one
current in every row interpolated from anchor chains, checked on held-out chains). Printed: ngspice's
CPU seconds (every child waited for), wall, decks, the ratio of the two, what ``chip.interp`` did per
array (its held-out difference), and the largest difference of every figure (signal, reset level,
AFE output, settling error) over every subpixel between the two runs - the independent check: the
exhaustive run simulated every one of the interpolated columns itself.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

from common import chip_slice, frame_runs

FIGURES = ("signal", "reset_level", "afe", "settling")


def main(argv) -> int:
    import numpy as np

    a, d, ph = chip_slice(argv, 50, "gradient")
    runs, frames = frame_runs(d, ph, {"exhaustive": {"interpolate": False}, "interpolated": {}}, "pk-bench-interp-")
    ex, fast = frames["exhaustive"], frames["interpolated"]
    diffs = {f"{k} {x}": round(float(np.nanmax(np.abs(getattr(ex, x)[k] - getattr(fast, x)[k]))) * 1e3, 4)
             for k in ("primary", "secondary") for x in FIGURES}
    out = {"design": Path(a.design).name, "rows": a.rows, "cols": a.cols, "scene": a.scene, "runs": runs,
           "cpu_ratio": round(runs["interpolated"]["cpu_s"] / runs["exhaustive"]["cpu_s"], 3),
           "wall_ratio": round(runs["interpolated"]["wall_s"] / runs["exhaustive"]["wall_s"], 3),
           "interpolated": [{k: v for k, v in r.items() if k != "columns"} for r in fast.interpolated],
           "max_diff_mV": diffs,
           "nan_cells": {n: int(sum(np.isnan(getattr(f, "signal")[k]).sum() for k in ("primary", "secondary")))
                         for n, f in frames.items()}}
    if a.json:
        print(json.dumps(out, indent=1))
        return 0
    print(f"{out['design']}, {a.rows} x {a.cols} with the AFE and the settling reads, scene {a.scene}:")
    for name, r in runs.items():
        print(f"  {name:12s} {r['cpu_s']:7.1f} s CPU, {r['wall_s']:6.1f} s wall, {r['decks']} decks, load {r['load']}")
    for r in fast.interpolated:
        held = "-" if r["max_diff_V"] is None else f"{r['max_diff_V'] * 1e3:.4f} mV"
        print(f"  {r['array']}: {'interpolated' if r['used'] else 'all simulated (' + r['why'] + ')'}: "
              f"{r['chains']} chains from {r['anchors']} anchors, held-out difference {held}")
    print(f"  interpolated / exhaustive: CPU {out['cpu_ratio']}, wall {out['wall_ratio']}")
    print("  largest difference from the exhaustive run (mV): " + ", ".join(f"{k} {v}" for k, v in diffs.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
