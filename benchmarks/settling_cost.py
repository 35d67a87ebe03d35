"""What the settling and over-exposure checks add to the design report's time.

    python3 benchmarks/settling_cost.py [--quick] [--json]

In one run, each step in a fresh process with its own empty ``PIXELKIT_CACHE``:

1. ``report_s``: ``pixelkit report designs/dual_pixel_revA.toml`` (full profile unless
   ``--quick``), as a user runs it;
2. ``settling_s``: the report's array frame (2 x 2, column chains with the AFE) with its
   long-S1/S2 reference reads minus the same frame without them;
3. ``bright_s``: the bright-source section's decks (``chip.bright.figures``).

``added_fraction`` = (settling_s + bright_s) / (report_s - settling_s - bright_s): the
share the checks add to the report without them. Limit (issue 27): 0.20. The machine's
load average is printed: the steps run one after the other, so a load change between them
moves the ratio.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REF = ROOT / "designs" / "dual_pixel_revA.toml"

_FRAME = """
import sys, time, numpy as np
from pixelkit.design import load_design
from pixelkit.chip.frame import simulate_frame
from pixelkit.chip.scene import default_map, photocurrents
d = load_design(sys.argv[1]); settle = sys.argv[2] == "1"
m, unit = default_map(2, 2 * d.secondary_per_pixel, "gradient")
ph = photocurrents(d, 2, 2, m, unit)
t = time.perf_counter()
simulate_frame(d, ph.iph_p, ph.iph_s, with_afe=True, split="columns", settling=settle, compression=ph.compression)
print(time.perf_counter() - t)
"""
_BRIGHT = """
import sys, time
from pixelkit.design import load_design
from pixelkit.chip.bright import FACTORS, QUICK_FACTORS, figures
d = load_design(sys.argv[1])
t = time.perf_counter()
figures(d, QUICK_FACTORS if sys.argv[2] == "1" else FACTORS)
print(time.perf_counter() - t)
"""


def _fresh_env(work: Path, name: str) -> dict:
    return {**os.environ, "PIXELKIT_CACHE": str(work / name), "PYTHONPATH": str(ROOT)}


def _py(code: str, env: dict, *args) -> float:
    p = subprocess.run([sys.executable, "-c", code, str(REF), *map(str, args)], capture_output=True, text=True,
                       env=env, cwd=ROOT)
    if p.returncode:
        raise SystemExit(p.stderr[-2000:])
    return float(p.stdout.strip().splitlines()[-1])


def measure(quick: bool = False) -> dict:
    work = Path(tempfile.mkdtemp(prefix="pk-bench-settling-"))
    load0 = os.getloadavg()
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "pixelkit", "report", str(REF), "--out", str(work / "report"),
                        "--json", *(["--quick"] if quick else [])], capture_output=True, text=True,
                       env=_fresh_env(work, "c_report"), cwd=ROOT)
    report_s = time.perf_counter() - t0
    if p.returncode not in (0, 1):
        raise SystemExit(f"pixelkit report exited {p.returncode}: {p.stderr[-2000:]}")
    with_ref = _py(_FRAME, _fresh_env(work, "c_frame1"), 1)
    without = _py(_FRAME, _fresh_env(work, "c_frame0"), 0)
    bright_s = _py(_BRIGHT, _fresh_env(work, "c_bright"), int(quick))
    settling_s = max(with_ref - without, 0.0)
    added = settling_s + bright_s
    return {"profile": "quick" if quick else "full", "report_s": round(report_s, 1),
            "frame_with_settling_s": round(with_ref, 2), "frame_without_s": round(without, 2),
            "settling_s": round(settling_s, 2), "bright_s": round(bright_s, 2),
            "added_fraction": round(added / max(report_s - added, 1e-9), 3),
            "within_limit_0_20": added <= 0.20 * (report_s - added),
            "load_avg_1min_start_end": [round(load0[0], 2), round(os.getloadavg()[0], 2)]}


def main() -> None:
    r = measure(quick="--quick" in sys.argv)
    if "--json" in sys.argv:
        print(json.dumps(r, indent=1))
        return
    print(f"report ({r['profile']} profile) from an empty cache: {r['report_s']} s; settling reference reads "
          f"{r['settling_s']} s (frame {r['frame_with_settling_s']} vs {r['frame_without_s']} s), bright-source "
          f"decks {r['bright_s']} s: they add {100 * r['added_fraction']:.1f} % to the rest "
          f"(limit 20 %: {'ok' if r['within_limit_0_20'] else 'OVER'})")
    print(f"  load average (1 min) at start / end: {r['load_avg_1min_start_end']}")


if __name__ == "__main__":
    main()
