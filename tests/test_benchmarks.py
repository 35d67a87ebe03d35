"""The benchmark suite runs to the end on the reference design: ``benchmarks/run.py --quick``; the
main job's runs merge only when they measured the same code (``benchmarks/main_job.py``).

Only that it completes and gives every figure, finite and of its kind, is checked here: the
figures themselves are times on a shared machine, measured as ratios by the script and quoted
with their load in docs/benchmarks.md (no wall-clock threshold in a test).
"""
import json
import math
import os
import subprocess
import sys

import pytest

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


def _main_job():
    import importlib.util
    spec = importlib.util.spec_from_file_location("main_job", ROOT / "benchmarks" / "main_job.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_main_job_merges_side_by_side_runs_of_the_same_code_only():
    mj = _main_job()
    a = {"head": "h1", "baseline": "b", "date": "2", "cores": 2, "jobs": 2, "parts": {"report": {}}}
    b = {"head": "h1", "baseline": None, "date": "1", "cores": 2, "jobs": 2, "parts": {"chip": {}}}
    m = mj.merged([a, b])
    assert list(m["parts"]) == ["report", "chip"] and m["baseline"] == "b" and m["date"] == "1"
    assert m["side_by_side"] == 2
    with pytest.raises(SystemExit, match="different code"):
        mj.merged([a, dict(b, head="h2")])
