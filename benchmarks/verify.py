"""The full sign-off of the reference design: cold, then again with nothing changed.

    python3 benchmarks/verify.py [--mc N] [--json]

Runs ``python3 -m pixelkit verify designs/dual_pixel_revA.toml --json`` as a user would
(its ``[verify]`` grid: 5 process corners x 3 temperatures x 3 supplies, Monte Carlo 200
unless ``--mc``) with ``PIXELKIT_CACHE`` set to a fresh empty folder (``cold_s``), then again
with nothing changed (``warm_s``: every deck from the simulation cache), and prints both,
the decks simulated, the CPU time of the command and its ngspice runs (on a machine others
load, wall time says little: CPU / cores is what an idle machine needs at least), the failing
specs (the reference design fails some: docs/verify.md) and the load average. Issue 31 targets on the 2-core machine: cold < 15 min, warm < 30 s.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import ROOT, child_cpu_s


def run(env: dict, out: Path, mc: str | None) -> tuple[float, dict, int, float]:
    cmd = [sys.executable, "-m", "pixelkit", "verify", str(ROOT / "designs" / "dual_pixel_revA.toml"),
           "--out", str(out), "--json", *(["--mc", mc] if mc else [])]
    t0, c0 = time.perf_counter(), child_cpu_s()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT)
    wall, cpu = time.perf_counter() - t0, child_cpu_s() - c0
    if p.returncode not in (0, 1, 4):
        raise SystemExit(f"pixelkit verify exited {p.returncode}: {p.stderr[-2000:]}")
    return wall, json.loads(p.stdout), p.returncode, cpu


def _decks(cache: Path) -> int:
    return sum(1 for _ in (cache / "sim").rglob("*.entry")) if (cache / "sim").is_dir() else 0


def measure(mc: str | None = None) -> dict:
    work = Path(tempfile.mkdtemp(prefix="pk-bench-verify-"))
    env = {**os.environ, "PIXELKIT_CACHE": str(work / "cache")}
    load0 = os.getloadavg()
    cold, r1, code1, cpu1 = run(env, work / "cold", mc)
    decks = _decks(work / "cache")
    load1 = os.getloadavg()
    warm, r2, code2, cpu2 = run(env, work / "warm", mc)
    same = [a["value"] for a in r1["rows"] if "value" in a] == [b["value"] for b in r2["rows"] if "value" in b]
    return {"conditions": r1["grid"]["conditions"], "mc_samples": r1["mc"]["samples"], "tasks": r1["tasks"],
            "cold_s": round(cold, 1), "warm_s": round(warm, 1), "cold_cpu_s": round(cpu1, 1),
            "warm_cpu_s": round(cpu2, 1), "cores": os.cpu_count(), "decks_simulated_cold": decks,
            "decks_simulated_warm": _decks(work / "cache") - decks, "same_table": same,
            "exit_status": [code1, code2], "failed_specs": r1["failed"], "unmeasured_specs": r1["unmeasured"],
            "simulation_errors": len(r1["errors"]),
            "load_avg_1min_start_mid_end": [round(load0[0], 2), round(load1[0], 2), round(os.getloadavg()[0], 2)],
            "cold_within_900_s": cold <= 900, "warm_within_30_s": warm <= 30}


def main() -> None:
    mc = sys.argv[sys.argv.index("--mc") + 1] if "--mc" in sys.argv else None
    r = measure(mc)
    if "--json" in sys.argv:
        print(json.dumps(r, indent=1))
        return
    print(f"verify, reference design, {r['conditions']} conditions + Monte Carlo {r['mc_samples']} "
          f"({r['tasks']} tasks): clean cache {r['cold_s']} s ({r['decks_simulated_cold']} decks); nothing changed "
          f"{r['warm_s']} s ({r['decks_simulated_warm']} decks), same table: {r['same_table']}")
    print(f"  CPU time (the command and its ngspice runs): cold {r['cold_cpu_s']} s, warm {r['warm_cpu_s']} s on "
          f"{r['cores']} cores: the wall time of an otherwise idle machine is at least CPU / cores")
    print(f"  load average (1 min) at start / between / end: {r['load_avg_1min_start_mid_end']}; failing specs: "
          f"{', '.join(r['failed_specs']) or 'none'}; simulation errors: {r['simulation_errors']}")
    print(f"  targets: cold <= 900 s {'met' if r['cold_within_900_s'] else 'MISSED'}, warm <= 30 s "
          f"{'met' if r['warm_within_30_s'] else 'MISSED'}")


if __name__ == "__main__":
    main()
