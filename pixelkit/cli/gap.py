"""``pixelkit gap predict | diagnose | selftest | emva``."""
from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from .common import design_arg, emit, json_opt, load, main, out_opt, output_path, spice_opts


@main.group()
def gap():
    """Diagnose the sim-to-real gap of measured data against the design."""


@gap.command()
@design_arg
@click.option("--conditions", type=click.Path(dir_okay=False), required=True)
@out_opt("predicted table (default: reports/<design>/predicted.csv)")
@spice_opts
@json_opt
def predict(design, conditions, out, backend, jobs, as_json):
    """Write the nominal prediction of every row of a conditions file (column v_nominal_V)."""
    from ..gap.data import read_table, write_table
    from ..gap.nominal import build_nominal, features
    from ..gap.nominal import predict as nominal_predict
    from ..progress import step
    d = load(design)
    out = output_path(out, d, "predicted.csv")
    table = read_table(conditions, d, measured=False)
    with step("building the SPICE-calibrated surrogate (first run only)"):
        nom = build_nominal(d, backend=backend)
    v = nominal_predict(nom, features(table, nom, d))
    write_table(table, out, {"v_nominal_V": v})
    emit({"out": str(out), "rows": len(table), "surrogate_error_V": nom.error}, as_json,
         lambda x: f"wrote {x['out']} ({x['rows']} rows; surrogate error vs SPICE: pixel "
                   f"{nom.error['pixel_max_V'] * 1e3:.2f} mV, AFE {nom.error['afe_max_V'] * 1e3:.2f} mV at worst)")


@gap.command()
@design_arg
@click.option("--measured", type=click.Path(dir_okay=False), required=True)
@out_opt("write an HTML section in this folder", folder=True)
@click.option("--seed", type=int, default=0, show_default=True, help="train / held-out split")
@spice_opts
@json_opt
def diagnose(design, measured, out, seed, backend, jobs, as_json):
    """Where the data leave the simulation, which effect explains it, how far the gap shrinks."""
    from ..gap.data import read_table
    from ..gap.diagnose import analyse
    from ..gap.nominal import build_nominal
    from ..progress import step
    out_dir = out
    d = load(design)
    table = read_table(measured, d, measured=True)
    with step("building the SPICE-calibrated surrogate (first run only)"):
        nom = build_nominal(d, backend=backend)
    r, X, resid = analyse(d, table, nom, seed=seed)
    if out_dir:
        from ..gap.report import write_section
        r["html"] = str(write_section(r, d.name, X, resid, Path(out_dir)))
    emit(r, as_json, _text)


def _text(r):
    lines = [f"best explanation: {r['best']}   held-out gap {r['gap_before_rms_V'] * 1e3:.2f} -> "
             f"{r['gap_after_rms_V'] * 1e3:.2f} mV rms (shrink {r['shrink_frac'] * 100:.0f} %)"]
    lines += [f"  {x['effect']:<18} held-out {x['heldout_rms_V'] * 1e3:8.3f} mV   BIC {x['bic']:9.1f}"
              for x in r["ranking"]]
    lines.append("where (significant first):")
    lines += [f"  {w['factor']:<16} {w['level']:<24} n={w['n']:<5} mean {w['mean_V'] * 1e3:+8.3f} mV  p={w['p']:.2g}"
              for w in r["where"][:10]]
    return "\n".join(lines)


@gap.command()
@click.argument("design", type=click.Path(dir_okay=False), required=False, default="designs/dual_pixel_revA.toml")
@click.option("--per-effect", type=click.IntRange(1, 1000), default=10, show_default=True)
@click.option("--clean", type=click.IntRange(0, 10000), default=20, show_default=True)
@click.option("--seed", type=int, default=1, show_default=True)
@spice_opts
@json_opt
def selftest(design, per_effect, clean, seed, backend, jobs, as_json):
    """Blind diagnosis of virtual measurements, each with one withheld effect (DESIGN: the reference)."""
    from ..gap.nominal import build_nominal
    from ..gap.selftest import run
    from ..progress import step
    d = load(design)
    with step("building the SPICE-calibrated surrogate (first run only)"):
        nom = build_nominal(d, backend=backend)
    r = run(d, nom, per_effect, clean, seed)
    emit(r, as_json, lambda x: "\n".join([
        f"{x['n_cases']} blind cases: top-1 {x['top1_accuracy'] * 100:.1f} %, median shrink "
        f"{x['median_shrink'] * 100:.1f} %, none on effect-free sets {x['none_on_clean'] * 100:.1f} %",
        "confusion (rows: truth, columns: found):",
        *(f"  {t:<18} " + " ".join(f"{n:>3}" for n in row.values()) for t, row in x["confusion"].items())]))


@gap.command()
@click.argument("dataset", type=click.Path(exists=True))
@json_opt
def emva(dataset, as_json):
    """Camera-level gap of an EMVA 1288 dataset: linear photon-transfer nominal, where, which, how far."""
    from ..gap.emva import analyse
    r = analyse(dataset)
    emit(r, as_json, lambda x: "\n".join([
        f"EMVA 1288 nominal: K = {x['nominal']['K_DN_per_e']:.4f} DN/e-, eta = {x['nominal']['eta']:.3f}, "
        f"dark {x['nominal']['dark_DN']:.2f} DN, sigma_dark {x['nominal']['sigma_dark_DN']:.3f} DN, "
        f"saturation {x['nominal']['mu_sat_DN']:.1f} DN ({x['nominal']['mu_e_sat']:.0f} e-)",
        *(f"  {w['region']:<26} n={w['n']:<3} mean residual {w['mean_resid_DN']:+.3f} DN, "
          f"variance {w['var_resid_rel'] * 100:+.1f} % vs PTC" for w in x["where"]),
        *(f"  {c['effect']:<16} held-out rms {c['heldout_rms_DN']:.3f} DN" for c in x["ranking"]),
        f"best: {x['best']} (held-out gap {x['gap_before_rms_DN']:.3f} -> {x['gap_after_rms_DN']:.3f} DN, "
        f"shrink {x['shrink_frac'] * 100:.0f} %)"]))
