"""The design report: full build from a clean cache (target < 10 min on 2 cores) and a re-run
with nothing changed (target < 30 s), measured in the same run.

    python3 benchmarks/report.py [--quick]

Prints wall times and their ratio as JSON. Measured times include whatever else runs on
the machine: say "under load" when quoting them.
"""
from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

from common import reference_design  # noqa: F401 - sets the import path and a fresh cache


def main(quick: bool) -> dict:
    design = reference_design()          # fresh, empty PIXELKIT_CACHE
    from pixelkit.report.build import build_report
    out = Path(tempfile.mkdtemp(prefix="pk-bench-report-")) / "revA"
    t0 = time.perf_counter()
    r1 = build_report(design, out, quick=quick)
    cold = time.perf_counter() - t0
    t0 = time.perf_counter()
    r2 = build_report(design, out, quick=quick)
    warm = time.perf_counter() - t0
    return {"profile": "quick" if quick else "full", "clean_cache_s": round(cold, 1), "unchanged_rerun_s": round(warm, 2),
            "rerun_over_clean": round(warm / cold, 4), "spice_runs_clean": r1["summary"]["spice_runs"],
            "sections_from_cache_rerun": r2["summary"]["sections_from_cache"], "failed": r1["failed"] + r2["failed"],
            "target_clean_s": 600, "target_rerun_s": 30}


if __name__ == "__main__":
    print(json.dumps(main("--quick" in sys.argv), indent=1))
