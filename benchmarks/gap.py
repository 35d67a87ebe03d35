"""Gap diagnosis speed against one SPICE experiment run, measured in the same run.

    python benchmarks/gap.py [--rows N] [--build]      (also a module of benchmarks/run.py)

- ``cold_cli_s``: ``pixelkit gap diagnose`` of one measured CSV (a committed
  virtual-silicon case, 56 rows) in a fresh process with an EMPTY simulation
  cache: importing the kit, reading the shipped surrogate, its key (76 of the
  build's 451 decks and every charge and amplitude) and its check against 4 fresh
  full-chain SPICE decks, fitting every candidate, printing the answer. Limit 10 s
  on 2 cores.
- ``diagnosis_s``: the diagnosis alone of an N-row dataset (default 2000 rows;
  the data come from the surrogate's own effect library, for timing only).
- ``build_s`` (``--build``): the surrogate built from SPICE with an empty cache
  (what a design with no shipped surrogate costs once).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from common import ROOT, THESIS_READ, reference_design
from pixelkit.experiments.thesis import run_experiment

CASE = "c1004"


def _case_csv(folder) -> str:
    import csv
    path = os.path.join(folder, "measured.csv")
    with open(ROOT / "pixelkit" / "gap" / "silicon_cases" / "cases.csv", newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r["case"] == CASE]
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, [k for k in rows[0] if k != "case"], extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    return path


def cold_cli() -> float:
    """Wall time of one `gap diagnose` in a fresh process with an empty cache."""
    with tempfile.TemporaryDirectory(prefix="pk-bench-gap-") as tmp:
        env = dict(os.environ, PIXELKIT_CACHE=os.path.join(tmp, "cache"), PYTHONPATH=str(ROOT))
        t0 = time.perf_counter()
        p = subprocess.run([sys.executable, "-m", "pixelkit", "gap", "diagnose",
                            str(THESIS_READ), "--measured", _case_csv(tmp), "--json"],
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
    from pixelkit.gap.store import read
    t0 = time.perf_counter()
    run_experiment(d)
    base = time.perf_counter() - t0
    out = {"spice_s": base, "cold_cli_s": cold_cli()}
    nom = read(d)
    rng = np.random.default_rng(7)
    table = selftest.campaign(d, nom, rng, n=rows)
    table.columns["v_V"], truth = selftest.measure(d, nom, table, "gse", rng)
    t0 = time.perf_counter()
    r = diagnose(d, table, nom)
    out.update({"diagnosis_s": time.perf_counter() - t0, "rows": rows, "models": len(r["ranking"]),
                "found": r["best"], "truth": truth["effect"]})
    if build:
        from pixelkit.gap.nominal import build_nominal
        os.environ["PIXELKIT_CACHE"] = tempfile.mkdtemp(prefix="pk-bench-")
        t0 = time.perf_counter()
        build_nominal(d)
        out["build_s"] = time.perf_counter() - t0
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", type=int, default=2000)
    ap.add_argument("--build", action="store_true")
    a = ap.parse_args()
    r = measure(reference_design(THESIS_READ), a.rows, a.build)
    base = r["spice_s"]
    print(f"baseline: one SPICE experiment run (16 decks)          {base:7.2f} s")
    print(f"gap diagnose, one measured CSV, cold cache, new process {r['cold_cli_s']:7.2f} s  "
          f"{r['cold_cli_s'] / base:5.2f} x baseline  (limit 10 s)")
    print(f"diagnosis of {r['rows']} rows, {r['models']} models incl. none   {r['diagnosis_s']:7.2f} s  "
          f"{r['diagnosis_s'] / base:5.2f} x baseline; found {r['found']} (truth {r['truth']})")
    if "build_s" in r:
        print(f"surrogate built from SPICE, empty cache               {r['build_s']:7.2f} s  "
              f"{r['build_s'] / base:5.2f} x baseline")
    print(f"load average (1 min): {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
