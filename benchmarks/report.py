"""The design report's build time: the full report from a clean cache, then again with nothing changed.

    python3 benchmarks/report.py [--quick] [--json]

Runs ``python3 -m pixelkit report designs/dual_pixel_revA.toml --json`` (the full profile
unless ``--quick``) as a user would, with ``PIXELKIT_CACHE`` set to a fresh empty folder,
times it (``cold_s``), then re-runs it with nothing changed (``warm_s``, served from the
section and simulation caches) and prints both, their ratio and the load average.
Issue 13 targets: cold within 600 s, warm within 30 s on the 2-core machine.
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


def run_report(out: Path, env: dict, quick: bool) -> tuple[float, dict]:
    cmd = [sys.executable, "-m", "pixelkit", "report", str(ROOT / "designs" / "dual_pixel_revA.toml"),
           "--out", str(out), "--json", *(["--quick"] if quick else [])]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT)
    wall = time.perf_counter() - t0
    if p.returncode not in (0, 1):
        raise SystemExit(f"pixelkit report exited {p.returncode}: {p.stderr[-2000:]}")
    return wall, json.loads(p.stdout)


def measure(quick: bool = False) -> dict:
    work = Path(tempfile.mkdtemp(prefix="pk-bench-report-"))
    env = {**os.environ, "PIXELKIT_CACHE": str(work / "cache")}
    load0 = os.getloadavg()
    cold, r1 = run_report(work / "cold", env, quick)
    warm, r2 = run_report(work / "warm", env, quick)
    return {"profile": "quick" if quick else "full", "cold_s": round(cold, 1), "warm_s": round(warm, 1),
            "cold_over_warm": round(cold / warm, 1),
            "cold_spice_runs": r1["spice_runs"], "warm_spice_runs": r2["spice_runs"],
            "warm_sections_from_cache": r2["sections_from_cache"],
            "failed_sections": r1["failed_sections"],
            "sections_available": sum(v == "available" for v in r1["sections"].values()),
            "load_avg_1min_start_end": [round(load0[0], 2), round(os.getloadavg()[0], 2)],
            "cold_within_600_s": cold <= 600, "warm_within_30_s": warm <= 30}


def main() -> None:
    r = measure(quick="--quick" in sys.argv)
    if "--json" in sys.argv:
        print(json.dumps(r, indent=1))
        return
    print(f"report ({r['profile']} profile), reference design, clean cache: {r['cold_s']} s "
          f"({r['cold_spice_runs']} SPICE runs); nothing changed: {r['warm_s']} s "
          f"({r['warm_spice_runs']} SPICE runs, {r['warm_sections_from_cache']} sections from cache); "
          f"ratio {r['cold_over_warm']}")
    print(f"  load average (1 min) at start / end: {r['load_avg_1min_start_end']}; "
          f"failed sections: {r['failed_sections'] or 'none'}")


if __name__ == "__main__":
    main()
