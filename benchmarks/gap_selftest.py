"""Blind diagnosis of the committed SPICE virtual silicon: every rate, with case counts and seeds.

    python benchmarks/gap_selftest.py [--sample FRACTION] [--json]

The cases are ``pixelkit/gap/silicon_cases`` (ngspice made them with each effect inserted as
circuit elements; ``truth.json`` holds each case's seed, elements and set-up). The rates are
the ones ``pixelkit gap selftest --kind spice --json`` prints; ``--sample`` diagnoses the
stratified sample the default tests use and estimates the whole set's rates with their 95 %
interval. The time is the diagnosis alone (the surrogate is read and checked first).
"""
from __future__ import annotations

import argparse
import json
import time

from common import THESIS_READ, reference_design
from pixelkit.gap import silicon
from pixelkit.gap.selftest import population, right_population, stratified_rate, stratified_sample
from pixelkit.gap.store import load_nominal


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sample", type=float, default=None, help="stratified sample fraction (default: every case)")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--cases-out", default=None, help="write every diagnosed case (truth, found, explained) as JSON")
    a = ap.parse_args()
    d = reference_design(THESIS_READ)
    nom = load_nominal(d)
    _, truths = silicon.load_cases()
    ids = stratified_sample(truths, a.sample) if a.sample else None
    t0 = time.perf_counter()
    r = silicon.run_committed(d, nom, only_ids=ids)
    wall = time.perf_counter() - t0
    if a.cases_out:
        with open(a.cases_out, "w") as fh:
            json.dump(r["cases"], fh)
    lib = [c for c in r["cases"] if c["truth"] not in ("none", "out_of_library")]
    right = [c for c in lib if c["found"] in c["accept"]]
    pop = population(truths)
    est = {"top1": stratified_rate(lib, pop, lambda c: c["found"] in c["accept"]),   # explained: per-stratum N
           "explained_when_right": stratified_rate(right, right_population(lib, pop),
                                                   lambda c: c["explained"] is True)}
    keys = ("n_cases", "n_effect_cases", "n_clean_cases", "n_out_of_library_cases", "top1_accuracy",
            "explained_when_right", "median_shrink", "none_on_clean", "not_explained_on_out_of_library",
            "uniform_named_uniform", "uniform_named_right", "uniform_visible_named_right", "mc_named_per_column",
            "two_effects_both_named", "dark_current_hot_named", "none_on_clean_calibrated", "seeds")
    out = {k: r[k] for k in keys} | {"per_effect_top1": r["per_effect_top1"], "diagnosis_s": wall,
                                     "sample_fraction": a.sample, "stratified_estimate": est}
    if a.json:
        print(json.dumps(out, indent=1))
        return
    for k in keys:
        print(f"{k:34s} {r[k]}")
    for k, v in est.items():
        print(f"{k + ' (whole set, stratified)':34s} {v['rate']:.3f} +- {v['half_width']:.3f} (worst-case +- "
              f"{v['half_width_worst']:.3f}; {v['n']} cases)")
    print(f"{'diagnosis wall time':34s} {wall:.1f} s for {r['n_cases']} cases")


if __name__ == "__main__":
    main()
