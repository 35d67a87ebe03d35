"""The benchmark suite runs to the end on the reference design: ``benchmarks/run.py --quick``; the
main job's figures on the pages are those of its stored run (``benchmarks/main_job.py``).

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


def test_main_job_figures_on_the_pages_are_the_stored_runs():
    """docs/benchmarks.md's main-job tables and the README's sentence on the first command's time
    are exactly what benchmarks/main_job.py renders from the stored run (no figure typed by hand;
    a page edited by hand, or a run stored without rewriting the pages, fails here). The stored run
    is a real one: parts of the main job, the report among them with its raw-ngspice replay, every
    part's SPICE runs accounted for by its figure groups."""
    mj = _main_job()
    res = json.loads(mj.RECORD.read_text())
    assert "report" in res["parts"] and set(res["parts"]) <= set(mj.PARTS), sorted(res["parts"])
    report = res["parts"]["report"]
    assert {"current", "raw"} <= set(report)
    for name, sides in res["parts"].items():
        c = sides["current"]
        assert (c["spice_runs"] > 0 or name in mj.WARM) and c["cpu_s"] > 0 and c["wall_s"] > 0 and sum(
            g["runs"] for g in c["groups"].values()) == c["spice_runs"]
        assert "log" not in c and "stderr_tail" not in c          # the record keeps no scratch paths
    assert mj.blocks(mj.DOCS_PAGE.read_text(), mj.DOCS_BEGIN, mj.DOCS_END) == mj.docs_block(res).strip()
    assert mj.blocks(mj.README.read_text(), mj.README_BEGIN, mj.README_END) == mj.readme_sentence(res).strip()


def test_main_job_merges_runs_each_part_with_its_code():
    mj = _main_job()
    a = {"head": "h1", "baseline": "b", "date": "2", "cores": 2, "jobs": 2, "parts": {"report": {}}}
    b = {"head": "h1", "baseline": None, "date": "1", "cores": 2, "jobs": 2, "parts": {"chip": {}}}
    m = mj.merged([a, b], code=lambda rev: rev)
    assert list(m["parts"]) == ["report", "chip"] and m["baseline"] == "b" and m["date"] == "1"
    assert m["runs"] == 2 and m["head"] == "h1" and m["code"] == {"report": "h1", "chip": "h1"}
    m = mj.merged([a, dict(b, head="h2")], code=lambda rev: rev)
    assert m["head"] is None and m["code"] == {"report": "h1", "chip": "h2"}
    stored = mj.merged([a, dict(b, head="h2")], code=lambda rev: rev)   # a record of mixed code, merged again
    m = mj.merged([dict(stored, parts={"chip": {}}), {**a, "head": "h3", "parts": {"afe4x4": {}}}], code=lambda rev: rev)
    assert m["code"] == {"chip": "h2", "afe4x4": "h3"} and m["head"] is None
    with pytest.raises(SystemExit, match="more than one run"):
        mj.merged([a, dict(b, parts={"report": {}})], code=lambda rev: rev)
    assert mj.code_commit("HEAD") == subprocess.run(["git", "-C", str(ROOT), "log", "-1", "--format=%h", "--", *mj.CODE], capture_output=True, text=True).stdout.strip()


def test_main_job_gives_the_baseline_its_copy_of_the_design_as_text(tmp_path):
    """The baseline's command line names its copy of the design (a Path from baseline_design) as a
    string, for every part that names a design (a Path there stopped the run at its first baseline part)."""
    mj = _main_job()
    for name, argv in mj.PARTS.items():
        designs = {x: tmp_path / "copy" / f"{k}.toml" for k, x in enumerate(argv) if x.endswith(".toml")}
        got = mj.part_argv(name, designs)
        assert all(isinstance(x, str) for x in got)
        assert [x for x in got if x.endswith(".toml")] == [str(v) for v in designs.values()]
        assert mj.part_argv(name, {}) == argv
