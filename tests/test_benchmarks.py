"""The benchmark suite runs to the end on the reference design: ``benchmarks/run.py --quick``.

Only that it completes and gives every figure, finite and of its kind, is checked here: the
figures themselves are times on a shared machine, measured as ratios by the script and quoted
with their load in docs/benchmarks.md (no wall-clock threshold in a test).
"""
import json
import math
import os
import subprocess
import sys

from conftest import ROOT

FIGURES = ("overhead_vs_raw", "kit_vs_raw_lib", "kit_outside_ngspice", "flattened_vs_lib", "parallel_speedup",
           "scaling_exponent", "analytic_points_per_s", "sizing_solve_s", "sizing_vs_spice", "gap_cold_cli_s",
           "gap_diagnosis_s", "gap_vs_spice")


def test_benchmark_suite_quick_profile_completes(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(ROOT), PIXELKIT_CACHE=str(tmp_path / "cache"), PIXELKIT_PROGRESS="0")
    p = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "run.py"), "--quick", "--json"], cwd=tmp_path,
                       env=env, capture_output=True, text=True, timeout=1800)
    assert p.returncode == 0, p.stderr[-3000:]
    r = json.loads(p.stdout)
    for k in FIGURES:
        assert isinstance(r[k], float) and math.isfinite(r[k]) and r[k] > 0, (k, r.get(k))
    assert set(r["frame_s"]) == {"2x2", "4x4"} and all(v > 0 for v in r["frame_s"].values())
    assert r["decks"] == 2 and r["points"] == 4 and r["workers"] >= 1
    assert "whole_array_s" not in r   # the quick profile leaves the whole chip out
