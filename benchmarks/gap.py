"""Gap diagnosis and surrogate build speed against one SPICE experiment run, measured in the same run.

    python benchmarks/gap.py [--design D] [--rows N] [--build]      (also a module of benchmarks/run.py)

- ``cold_cli_s``: ``pixelkit gap diagnose`` of one measured CSV (a committed virtual-silicon case of the
  design: the thesis [Thesis2019] read's ``silicon_cases``, the reference's out-of-distribution development set) in a
  fresh process with an EMPTY simulation cache: importing the kit, reading the shipped surrogate, its key
  and its check against 4 fresh full-chain SPICE decks, fitting every candidate, printing the answer.
  Limit 10 s on 2 cores.
- ``diagnosis_s``: the diagnosis alone of an N-row dataset (default 2000 rows; the data come from the
  surrogate's own effect library, for timing only).
- ``build_s`` / ``build_cpu_s`` (``--build``): the surrogate built from SPICE with an empty cache (what a
  design with no shipped surrogate costs once; wall and CPU of the kit and its ngspice children), its
  deck count, and ``rebuild_s``: the same build for a revision that changes only the secondary subpixel
  (its PD 10 % wider) with the first build's cache (the packed decks of the primary are the same decks:
  the engine's cache serves them).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from common import ROOT, child_cpu_s, reference_design
from pixelkit.experiments.thesis import run_experiment

#: a committed case of each design with one: (cases folder, case id)
CASES = {"dual_pixel_revA_thesis_read": (ROOT / "pixelkit" / "gap" / "silicon_cases", "c1004"),
         "dual_pixel_revA": (ROOT / "tests" / "data" / "gap_ood" / "dev", "c50004")}


def _case_csv(folder, design) -> str:
    import csv
    path = os.path.join(folder, "measured.csv")
    cases, cid = CASES[design.name]
    with open(cases / "cases.csv", newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r["case"] == cid]
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, [k for k in rows[0] if k != "case"], extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    return path


def cold_cli(design) -> float:
    """Wall time of one `gap diagnose` in a fresh process with an empty cache."""
    with tempfile.TemporaryDirectory(prefix="pk-bench-gap-") as tmp:
        env = dict(os.environ, PIXELKIT_CACHE=os.path.join(tmp, "cache"), PYTHONPATH=str(ROOT))
        t0 = time.perf_counter()
        p = subprocess.run([sys.executable, "-m", "pixelkit", "gap", "diagnose",
                            str(design.source), "--measured", _case_csv(tmp, design), "--json"],
                           capture_output=True, text=True, env=env, cwd=tmp)
        wall = time.perf_counter() - t0
        if p.returncode != 0:
            raise SystemExit(f"gap diagnose failed: {p.stderr}")
        if "building it from SPICE" in p.stderr:
            raise SystemExit("the shipped surrogate was not used (its check failed): " + p.stderr)
    return wall


def measure(d, rows: int = 2000, build: bool = False) -> dict:
    """Wall times (s): one SPICE experiment run, the cold CLI diagnosis, an N-row diagnosis."""
    from pixelkit.gap import selftest
    from pixelkit.gap.diagnose import diagnose
    from pixelkit.gap.store import load_nominal
    t0 = time.perf_counter()
    run_experiment(d)
    base = time.perf_counter() - t0
    out = {"spice_s": base, "cold_cli_s": cold_cli(d)}
    nom = load_nominal(d)
    rng = np.random.default_rng(7)
    table = selftest.campaign(d, nom, rng, n=rows)
    table.columns["v_V"], truth = selftest.measure(d, nom, table, "gse", rng)
    t0 = time.perf_counter()
    r = diagnose(d, table, nom)
    out.update({"diagnosis_s": time.perf_counter() - t0, "rows": rows, "models": len(r["ranking"]),
                "found": r["best"], "truth": truth["effect"]})
    if build:
        out.update(build_times(d))
    return out


def build_times(d) -> dict:
    """The surrogate's build from an empty cache (wall, CPU, decks), then a secondary-only revision's."""
    from dataclasses import replace

    from pixelkit.gap import buildplan
    from pixelkit.gap.nominal import build_nominal, grids
    os.environ["PIXELKIT_CACHE"] = tempfile.mkdtemp(prefix="pk-bench-")
    decks = sum(len(js) for js in buildplan.plan(d, grids(d), {"primary": 0.0, "secondary": 0.0}))
    c0, t0 = time.process_time() + child_cpu_s(), time.perf_counter()
    build_nominal(d)
    out = {"build_s": time.perf_counter() - t0, "build_cpu_s": time.process_time() + child_cpu_s() - c0,
           "build_decks": decks}
    rev = replace(d, secondary=replace(d.secondary, pd_width=d.secondary.pd_width * 1.1))
    t0 = time.perf_counter()
    build_nominal(rev)
    out["rebuild_s"] = time.perf_counter() - t0
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", type=int, default=2000)
    ap.add_argument("--build", action="store_true")
    ap.add_argument("--design", default=str(ROOT / "designs" / "dual_pixel_revA.toml"))
    a = ap.parse_args()
    r = measure(reference_design(a.design), a.rows, a.build)
    base = r["spice_s"]
    print(f"baseline: one SPICE experiment run (16 decks)          {base:7.2f} s")
    print(f"gap diagnose, one measured CSV, cold cache, new process {r['cold_cli_s']:7.2f} s  "
          f"{r['cold_cli_s'] / base:5.2f} x baseline  (limit 10 s)")
    print(f"diagnosis of {r['rows']} rows, {r['models']} models incl. none   {r['diagnosis_s']:7.2f} s  "
          f"{r['diagnosis_s'] / base:5.2f} x baseline; found {r['found']} (truth {r['truth']})")
    if "build_s" in r:
        print(f"surrogate built from SPICE, empty cache, {r['build_decks']} decks     {r['build_s']:7.2f} s  "
              f"{r['build_s'] / base:5.2f} x baseline; CPU {r['build_cpu_s']:.1f} s (kit + ngspice)")
        print(f"a secondary-only revision's surrogate, warm cache     {r['rebuild_s']:7.2f} s  "
              f"{r['rebuild_s'] / base:5.2f} x baseline")
    print(f"load average (1 min): {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
