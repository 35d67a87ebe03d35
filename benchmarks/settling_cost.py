"""What the settling and over-exposure checks add to the design report's time.

    python3 benchmarks/settling_cost.py [--quick] [--json] [DESIGN.toml]

On ``DESIGN.toml`` (default: the reference design, ``designs/dual_pixel_revA.toml``, whatever
it holds), in one run, each step in a fresh process with its own empty ``PIXELKIT_CACHE``:

1. ``report_s``: ``pixelkit report DESIGN.toml`` (full profile unless ``--quick``), as a user
   runs it;
2. ``settling_s``: the report's array frame (2 x 2, column chains with the AFE) with its
   long-S1/S2 reference reads minus the same frame without them;
3. ``bright_s``: the bright-source section's decks (``chip.bright.figures``).

``added_fraction`` = (settling_s + bright_s) / (report_s - settling_s - bright_s): the
share the checks add to the report without them. Limit (issue 27): 0.20. Each step is timed
in wall time and in CPU time (the process and every process it waited for: ngspice); the
limit is judged on CPU time, which the shared machine's load does not move (the wall ratio
does: the steps run one after the other). The quick profile's bright-source step is what its
report runs: the design's own anti-blooming setting at 1 and 1000 full wells.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import child_cpu_s

ROOT = Path(__file__).resolve().parents[1]
REF = ROOT / "designs" / "dual_pixel_revA.toml"

_CPU = """
import resource, time
def cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + r.ru_utime + r.ru_stime
"""
_FRAME = _CPU + """
import sys, time, numpy as np
from pixelkit.design import load_design
from pixelkit.chip.frame import simulate_frame
from pixelkit.chip.scene import default_map, photocurrents
d = load_design(sys.argv[1]); settle = sys.argv[2] == "1"
m, unit = default_map(2, 2 * d.secondary_per_pixel, "gradient")
ph = photocurrents(d, 2, 2, m, unit)
t, c = time.perf_counter(), cpu()
simulate_frame(d, ph.iph_p, ph.iph_s, with_afe=True, split="columns", settling=settle, compression=ph.compression)
print(time.perf_counter() - t, cpu() - c)
"""
_BRIGHT = _CPU + """
import sys, time
from pixelkit.design import load_design
from pixelkit.chip.bright import FACTORS, HOLDS, QUICK_FACTORS, figures
d = load_design(sys.argv[1])
t, c = time.perf_counter(), cpu()
quick = sys.argv[2] == "1"
figures(d, QUICK_FACTORS if quick else FACTORS, holds=(None,) if quick else HOLDS)
print(time.perf_counter() - t, cpu() - c)
"""


def _fresh_env(work: Path, name: str) -> dict:
    return {**os.environ, "PIXELKIT_CACHE": str(work / name), "PYTHONPATH": str(ROOT)}


def _py(code: str, env: dict, design: Path, *args) -> tuple[float, float]:
    """(wall s, CPU s) the snippet prints for its own timed part."""
    p = subprocess.run([sys.executable, "-c", code, str(design), *map(str, args)], capture_output=True, text=True,
                       env=env, cwd=ROOT)
    if p.returncode:
        raise SystemExit(p.stderr[-2000:])
    wall, cpu = p.stdout.strip().splitlines()[-1].split()
    return float(wall), float(cpu)


def _share(report, settling, bright) -> dict:
    added = settling + bright
    return {"report_s": round(report, 1), "settling_s": round(settling, 2), "bright_s": round(bright, 2),
            "added_fraction": round(added / max(report - added, 1e-9), 3)}


def measure(quick: bool = False, design: Path = REF) -> dict:
    work = Path(tempfile.mkdtemp(prefix="pk-bench-settling-"))
    load0 = os.getloadavg()
    t0, c0 = time.perf_counter(), child_cpu_s()
    p = subprocess.run([sys.executable, "-m", "pixelkit", "report", str(design), "--out", str(work / "report"),
                        "--json", *(["--quick"] if quick else [])], capture_output=True, text=True,
                       env=_fresh_env(work, "c_report"), cwd=ROOT)
    report = (time.perf_counter() - t0, child_cpu_s() - c0)
    if p.returncode not in (0, 1):
        raise SystemExit(f"pixelkit report exited {p.returncode}: {p.stderr[-2000:]}")
    with_ref = _py(_FRAME, _fresh_env(work, "c_frame1"), design, 1)
    without = _py(_FRAME, _fresh_env(work, "c_frame0"), design, 0)
    bright = _py(_BRIGHT, _fresh_env(work, "c_bright"), design, int(quick))
    wall = _share(report[0], max(with_ref[0] - without[0], 0.0), bright[0])
    cpu = _share(report[1], max(with_ref[1] - without[1], 0.0), bright[1])
    return {"design": design.name, "profile": "quick" if quick else "full", "wall": wall, "cpu": cpu,
            "frame_with_settling_s": [round(with_ref[0], 2), round(with_ref[1], 2)],
            "frame_without_s": [round(without[0], 2), round(without[1], 2)],
            "within_limit_0_20": cpu["added_fraction"] <= 0.20,
            "load_avg_1min_start_end": [round(load0[0], 2), round(os.getloadavg()[0], 2)]}


def main() -> None:
    paths = [Path(a).resolve() for a in sys.argv[1:] if not a.startswith("--")]
    r = measure(quick="--quick" in sys.argv, design=paths[0] if paths else REF)
    if "--json" in sys.argv:
        print(json.dumps(r, indent=1))
        return
    for kind in ("cpu", "wall"):
        x = r[kind]
        print(f"{kind:>4}: {r['design']}, report ({r['profile']} profile) from an empty cache {x['report_s']} s; "
              f"settling reference reads {x['settling_s']} s, bright-source decks {x['bright_s']} s: they add "
              f"{100 * x['added_fraction']:.1f} % to the rest")
    print(f"  frame with / without its settling reads (wall, CPU s): {r['frame_with_settling_s']} / "
          f"{r['frame_without_s']}; limit 20 % (CPU): {'ok' if r['within_limit_0_20'] else 'OVER'}")
    print(f"  load average (1 min) at start / end: {r['load_avg_1min_start_end']}")


if __name__ == "__main__":
    main()
