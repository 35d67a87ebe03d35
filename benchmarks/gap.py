"""Gap diagnosis speed: a 2000-row dataset, all candidates, against one SPICE experiment run.

    python benchmarks/gap.py [rows]      (also a module of benchmarks/run.py)
"""
from __future__ import annotations

import sys
import time

import numpy as np

from common import reference_design
from pixelkit.experiments.thesis import run_experiment
from pixelkit.gap import selftest
from pixelkit.gap.diagnose import diagnose
from pixelkit.gap.nominal import build_nominal


def measure(d, rows: int = 2000) -> dict:
    """Wall times (s) of one SPICE experiment run, the nominal surrogate and the diagnosis."""
    t0 = time.perf_counter()
    run_experiment(d)
    base = time.perf_counter() - t0
    t0 = time.perf_counter()
    nom = build_nominal(d)
    t_nom = time.perf_counter() - t0
    rng = np.random.default_rng(7)
    table = selftest.campaign(d, nom, rng, n=rows)
    table.columns["v_V"], truth = selftest.measure(d, nom, table, "gse", rng)
    t0 = time.perf_counter()
    r = diagnose(d, table, nom)
    return {"spice_s": base, "nominal_s": t_nom, "diagnosis_s": time.perf_counter() - t0,
            "models": len(r["ranking"]), "found": r["best"], "truth": truth["effect"]}


def main(rows: int = 2000):
    r = measure(reference_design(), rows)
    base, t_nom, t_diag = r["spice_s"], r["nominal_s"], r["diagnosis_s"]
    print(f"baseline: one SPICE experiment run (16 decks)        {base:7.2f} s")
    print(f"nominal surrogate (54 full-chain decks, uncached)    {t_nom:7.2f} s  {t_nom / base:5.2f} x baseline")
    print(f"diagnosis of {rows} rows, {r['models']} models incl. none  {t_diag:7.2f} s  "
          f"{t_diag / base:5.2f} x baseline")
    print(f"total {t_nom + t_diag:.1f} s (limit 60 s); found {r['found']} (truth {r['truth']})")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 2000)
