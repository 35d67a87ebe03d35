"""``pixelkit gap predict | diagnose | plan | selftest | silicon | surrogate | emva``."""
from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from .common import design_arg, emit, json_opt, load, main, out_opt, output_path, spice_opts, post_layout_opt
from .types import FilePath, FiniteRange

#: The chip the kit's committed SPICE cases (``pixelkit/gap/silicon_cases``) are of: the read of [Thesis2019]
#: (docs/gap-diagnosis.md). ``gap selftest`` and ``gap silicon`` use it only when no DESIGN is given; a DESIGN
#: given is the one diagnosed, and data of another design are refused, never diagnosed against it.
THESIS_READ = "designs/dual_pixel_revA_thesis_read.toml"
CASES_OF = "dual_pixel_revA_thesis_read"


def _committed_cases_of(d, what: str, option: str) -> None:
    """Refuse the kit's committed SPICE cases for a design they are not of (exit 2, naming ``option``)."""
    if d.name != CASES_OF:
        from ..errors import ConfigError
        raise ConfigError(what, option, "the kit's pixelkit/gap/silicon_cases",
                          f"SPICE cases of {d.name}: the kit's are of {CASES_OF} ({THESIS_READ}); make this design's "
                          f"with `pixelkit gap silicon DESIGN --out FOLDER` and pass --spice-cases FOLDER, or run "
                          f"--kind surrogate")


@main.group()
def gap():
    """Diagnose the sim-to-real gap of measured data against the design."""


@gap.command()
@design_arg
@click.option("--conditions", type=FilePath(dir_okay=False), required=True)
@out_opt("predicted table (default: reports/<design>/predicted.csv)")
@spice_opts
@post_layout_opt
@json_opt
def predict(design, conditions, out, backend, jobs, as_json):
    """Write the nominal prediction of every row of a conditions file (column v_nominal_V)."""
    from ..gap.data import read_table, write_table
    from ..gap.nominal import features
    from ..gap.nominal import predict as nominal_predict
    from ..gap.store import load_nominal
    from ..progress import step
    role = _role_design(design, "gap predict")
    if role is not None:   # a pixel read by role: its own benches, every row simulated
        from ..rolepix.gap import predict as role_predict, read
        out = output_path(out, role, "predicted.csv")
        table = read(conditions, role, measured=False)
        with step("simulating every row on the pixel's true-CDS benches"):
            v = role_predict(role, table, backend=backend, jobs=jobs)
        _write_role(conditions, out, v)
        emit({"out": str(out), "rows": len(v)}, as_json, lambda x: f"wrote {x['out']} ({x['rows']} rows, each simulated)")
        return
    d = load(design)
    out = output_path(out, d, "predicted.csv")
    table = read_table(conditions, d, measured=False)
    with step("building the SPICE-calibrated surrogate (first run only)"):
        nom = load_nominal(d, backend=backend)
    v = nominal_predict(nom, features(table, nom, d))
    write_table(table, out, {"v_nominal_V": v})
    emit({"out": str(out), "rows": len(table), "surrogate_error_V": nom.error}, as_json,
         lambda x: f"wrote {x['out']} ({x['rows']} rows; surrogate error vs SPICE: pixel "
                   f"{nom.error['pixel_max_V'] * 1e3:.2f} mV, AFE {nom.error['afe_max_V'] * 1e3:.2f} mV at worst)")


def setup_opts(f):
    f = click.option("--gain-tol", type=FiniteRange(0.0, 0.5), default=0.05, show_default=True,
                     help="plausible test set-up gain: 1 +- this")(f)
    f = click.option("--offset-tol", type=FiniteRange(0.0, 1.0), default=0.025, show_default=True,
                     help="plausible test set-up offset: +- this (V)")(f)
    f = click.option("--gain-sd", type=FiniteRange(0.0, 0.5, min_open=True), default=None,
                     help="the bench's calibration: each probe's gain known to 1 +- this (one standard deviation); "
                          "default: not stated")(f)
    return click.option("--offset-sd", type=FiniteRange(0.0, 1.0, min_open=True), default=None,
                        help="the bench's calibration: each probe's offset known to 0 +- this (V, one standard "
                             "deviation); default: not stated")(f)


def _setup(gain_tol, offset_tol, gain_sd, offset_sd):
    from ..gap.fit import SetupBounds
    return SetupBounds(gain_tol, offset_tol, gain_sd, offset_sd)


def _prepare(design, measured, backend):
    from ..gap.data import read_table
    from ..gap.store import load_nominal
    from ..progress import step
    d = load(design)
    table = read_table(measured, d, measured=True)
    with step("building the SPICE-calibrated surrogate (first run only)"):
        nom = load_nominal(d, backend=backend)
    return d, table, nom


@gap.command()
@design_arg
@click.option("--measured", type=FilePath(), required=True,
              help="a gap table (CSV) or an EMVA 1288 dataset (folder, or its EMVA1288_Data.txt)")
@out_opt("write an HTML section in this folder", folder=True)
@click.option("--seed", type=int, default=0, show_default=True, help="train / held-out split")
@setup_opts
@spice_opts
@post_layout_opt
@json_opt
def diagnose(design, measured, out, seed, gain_tol, offset_tol, gain_sd, offset_sd, backend, jobs, as_json):
    """Where the data leave the simulation, which effect explains it, whether the gap is explained.

    MEASURED is a gap table (CSV, docs/howto-measurements.md) or an EMVA 1288 dataset (its folder or its
    EMVA1288_Data.txt): a camera's is diagnosed at camera level against the standard's linear model, as
    ``gap emva`` does, in the same verdict words."""
    from ..gap.diagnose import analyse
    if _is_emva(measured):
        from ..gap.emva import analyse as camera
        load(design)   # a bad design file is still refused by name
        r = camera(measured)
        r["design_note"] = ("an EMVA 1288 dataset is a camera's: diagnosed against the standard's linear model of its "
                            "own photon transfer; the design's surrogate does not enter")
        emit(r, as_json, _emva_text)
        return
    role = _role_design(design, "gap diagnose")
    if role is not None:   # a pixel read by role: its own effects on its own benches
        from ..errors import ConfigError
        from ..progress import step
        from ..rolepix.gap import Setup, diagnose as role_diagnose, read
        if out is not None:
            raise ConfigError("gap diagnose", "--out", out, f"no --out for a {role.family} design (its diagnosis "
                              "writes no HTML section: docs/gap-diagnosis.md)")
        setup = Setup(gain_sd, offset_sd) if gain_sd is not None or offset_sd is not None else None
        table = read(measured, role, measured=True)
        with step("simulating the rows and each candidate effect on the pixel's benches"):
            r = role_diagnose(role, table, backend=backend, jobs=jobs, setup=setup)
        emit(r, as_json, _role_text)
        return
    d, table, nom = _prepare(design, measured, backend)
    r, X, resid = analyse(d, table, nom, seed=seed, setup=_setup(gain_tol, offset_tol, gain_sd, offset_sd))
    if out:
        from ..gap.report import write_section
        r["html"] = str(write_section(r, d.name, X, resid, Path(out)))
    emit(r, as_json, _text)


def _role_design(path, command: str):
    """The design at ``path`` when it is a pixel read by role (``--post-layout`` refused), else None."""
    from ..family import ROLE_FAMILIES, family_of
    fam = family_of(path)
    if fam not in ROLE_FAMILIES:
        return None
    from .common import load_role
    return load_role(path, fam, command)


def _write_role(conditions, out, v) -> None:
    """The conditions file's rows and columns as read, with ``v_nominal_V``."""
    import csv
    import io
    from ..fileio import write_atomic
    from ..gap.data import read_rows
    header, rows, _src = read_rows(conditions, measured=False)
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow([*header, "v_nominal_V"])
    for r, x in zip(rows, v):
        w.writerow([*(r[h] for h in header), f"{float(x):.9g}"])
    write_atomic(out, buf.getvalue())


def _role_text(r) -> str:
    lines = [f"verdict: {r['verdict']}",
             f"{r['n_rows']} rows: fitted on {r['n_train']}, judged on the held-out rows "
             f"{', '.join(map(str, r['heldout_rows']))}",
             f"held-out rows: noise {r['noise_rms_V'] * 1e3:.3g} mV rms; gap {r['gap_before_rms_V'] * 1e3:.3g} mV rms "
             f"against the nominal read, {r['gap_after_rms_V'] * 1e3:.3g} mV with {r['best']}",
             "candidates (least held-out chi-square first):"]
    for k in r["ranking"]:
        f = r["fits"][k]
        lines.append(f"  {k:<18} {f['value']:.4g} {f['unit']}{' (at its bound)' if f['at_bound'] else ''}  "
                     f"held-out chi2 {f['heldout_chi2']:.4g} over {r['n_heldout']} rows, p = {f['p_value']:.3g}"
                     f"{'' if f['beats_nominal'] else ' (does not beat the nominal there)'}")
    lines.append(f"  {'none':<18} held-out chi2 {r['nominal_chi2']:.4g}, p = {r['nominal_p_value']:.3g}")
    su = r.get("setup")
    if su and su["stated"]:
        lines.append(f"set-up (stated calibration): gain {su['gain']:.4f}, offset {su['offset_V'] * 1e3:+.3f} mV "
                     f"with {r['best']}")
    nz = r.get("noise")
    if nz is not None:
        lines.append(f"noise (v_std_V): {nz['verdict']}; the nominal read's chi2 {nz['nominal_chi2']:.4g}, p = "
                     f"{nz['nominal_p_value']:.3g}; with {nz['share']:.3g} of FD's kT/C chi2 {nz['chi2']:.4g}, p = "
                     f"{nz['p_value']:.3g}" if nz["run"] else f"noise (v_std_V): not read: {nz['why']}")
    return "\n".join(lines)


def _is_emva(path) -> bool:
    """A dataset folder holding EMVA1288_Data.txt, or that descriptor itself."""
    p = Path(path)
    return (p.is_dir() and (p / "EMVA1288_Data.txt").is_file()) or p.name == "EMVA1288_Data.txt"


def _text(r):
    noise = f"{r['noise_rms_V'] * 1e3:.2f} mV" if r["noise_rms_V"] else "unknown"
    moved = [p for p, v in r.get("probes", {}).items() if v["moved"]]
    lines = [f"verdict: {r['verdict']}",
             f"where: {r['position']}" + (f"; the probes that moved beyond their noise: {', '.join(moved)}"
                                          if r.get("probes") else ""),
             f"best: {r['best']}   held-out gap {r['gap_before_rms_V'] * 1e3:.2f} -> "
             f"{r['gap_after_rms_V'] * 1e3:.2f} mV rms (shrink {r['shrink_frac'] * 100:.0f} %); noise {noise} "
             f"({r['noise_source']}); held-out chi2/row {r['heldout_chi2_per_row']:.2f}"]
    lines += [f"  {x['effect']:<18} held-out {x['heldout_rms_V'] * 1e3:8.3f} mV   BIC {x['bic']:11.1f}"
              f"{'   beats none' if x['beats_none'] else ''}" for x in r["ranking"]]
    lines.append("bench calibration: " + _calibration_text(r["calibration"]))
    if r["remainder_where"]:
        lines.append("the remainder lies in:")
        lines += [f"  {w['factor']:<16} {w['level']:<24} mean {w['mean_V'] * 1e3:+8.3f} mV  p={w['p']:.2g}"
                  for w in r["remainder_where"]]
    lines.append("where the data leave the nominal model (significant first):")
    lines += [f"  {w['factor']:<16} {w['level']:<24} n={w['n']:<5} mean {w['mean_V'] * 1e3:+8.3f} mV  p={w['p']:.2g}"
              for w in r["where"][:10]]
    return "\n".join(lines)


def _calibration_text(cal):
    if not cal["stated"]:
        return cal["note"]
    gain = "not stated" if cal["gain_sd"] is None else f"+-{cal['gain_sd']:.2%}"
    off = "not stated" if cal["offset_sd_V"] is None else f"+-{cal['offset_sd_V'] * 1e3:g} mV"
    return (f"gain {gain}, offset {off} (one sd, per probe); the named model's set-up sits at chi2 "
            f"{cal['chi2']:.1f} ({cal['terms']} terms) from it")


@gap.command()
@design_arg
@click.option("--measured", type=FilePath(dir_okay=False), required=True)
@click.option("--top", type=click.IntRange(1, 50), default=5, show_default=True)
@setup_opts
@spice_opts
@json_opt
def plan(design, measured, top, gain_tol, offset_tol, gain_sd, offset_sd, backend, jobs, as_json):
    """Operating points that would separate the candidates these data cannot tell apart."""
    from ..gap.diagnose import diagnose as run_diagnose
    from ..gap.plan import plan as make_plan
    d, table, nom = _prepare(design, measured, backend)
    setup = _setup(gain_tol, offset_tol, gain_sd, offset_sd)
    r = run_diagnose(d, table, nom, setup=setup)
    p = make_plan(d, table, nom, r, setup, top)
    p["diagnosis"] = {"best": r["best"], "indistinguishable": r["indistinguishable"], "verdict": r["verdict"]}
    emit(p, as_json, lambda x: "\n".join([
        f"candidates: {', '.join(x['candidates'])} (noise {x['noise_V'] * 1e3:.2f} mV per measurement)",
        "vary (alone, from the data's median point):",
        *(f"  {lv['factor']:<13} -> {lv['value']:<8g} separation {lv['separation_sigma']:.1f} sigma"
          if not isinstance(lv["value"], str) else
          f"  {lv['factor']:<13} -> {lv['value']:<8} separation {lv['separation_sigma']:.1f} sigma" for lv in x["levers"]),
        "best operating points:",
        *(f"  {pt['separation_sigma']:7.1f} sigma  " + ", ".join(f"{k}={v}" for k, v in pt["point"].items())
          for pt in x["points"]),
        *(["what these data lack:"] + [f"  {m}" for m in x["measurements"]] if x.get("measurements") else []),
        "the measurement that separates each pair:",
        *(f"  {pair}: {v['separation_sigma']:.1f} sigma at " + ", ".join(f"{k}={w}" for k, w in v["point"].items())
          for pair, v in x["pairs"].items())]))


@gap.command()
@click.argument("design", type=FilePath(dir_okay=False), required=False, default=None)
@click.option("--per-effect", type=click.IntRange(1, 1000), default=10, show_default=True)
@click.option("--clean", type=click.IntRange(0, 10000), default=20, show_default=True)
@click.option("--rows", type=click.IntRange(40, 100000), default=240, show_default=True,
              help="rows per surrogate-generated case")
@click.option("--seed", type=int, default=1, show_default=True)
@click.option("--spice-cases", type=FilePath(file_okay=False), default=None,
              help="folder of committed SPICE cases (default: the kit's pixelkit/gap/silicon_cases)")
@click.option("--kind", type=click.Choice(["both", "surrogate", "spice"]), default="both", show_default=True)
@click.option("--ood", type=click.Choice(["dev", "heldout", "heldout2", "both"]), default=None,
              help="instead: the out-of-distribution virtual silicon (tests/data/gap_ood, of the reference design "
                   "dual_pixel_revA: DESIGN, when given, must be it): "
                   "its development set, its first held-out set (seen), its second (seeds 90000-) or dev + heldout")
@spice_opts
@json_opt
def selftest(design, per_effect, clean, rows, seed, spice_cases, kind, ood, backend, jobs, as_json):
    """Blind diagnosis of DESIGN (default: the thesis read, whose SPICE cases the kit commits): surrogate-generated
    cases and SPICE-generated cases, reported separately; or (--ood) the out-of-distribution virtual silicon."""
    from ..gap import silicon
    from ..gap.store import load_nominal
    from ..gap.selftest import run
    from ..progress import step
    from ..spice.engine import default_jobs
    if ood:
        from ..gap import ood as ood_mod
        sets = ("dev", "heldout") if ood == "both" else (ood,)
        for s in sets:
            if not (ood_mod.OOD_DIR / s / "truth.json").is_file():
                raise click.UsageError(f"--ood {ood}: the {s} set is not in {ood_mod.OOD_DIR} (not generated yet)")
        d = load(design or ood_mod.DESIGN)
        ref = load(ood_mod.DESIGN) if design else d
        if d.name != ref.name:   # the sets are lab data of the reference design: never diagnosed against another
            from ..errors import ConfigError
            raise ConfigError("gap selftest", "DESIGN", str(design),
                              f"the reference design {ref.name} with --ood (its sets are that design's data), or "
                              f"no DESIGN")
        with step("loading the SPICE-calibrated surrogate"):
            nom = load_nominal(d, backend=backend)
        r = {f"ood_{s}": ood_mod.run_set(d, nom, s) for s in sets}
        emit(r, as_json, lambda x: "\n".join(_selftest_text(k, v) for k, v in x.items()))
        return
    d = load(design or THESIS_READ)
    if kind in ("both", "spice") and spice_cases is None:
        _committed_cases_of(d, "gap selftest", "--spice-cases")
    with step("building the SPICE-calibrated surrogate (first run only)"):
        nom = load_nominal(d, backend=backend)
    r = {}
    if kind in ("both", "surrogate"):
        r["surrogate"] = run(d, nom, per_effect, clean, seed, rows)
    if kind in ("both", "spice"):
        r["spice"] = silicon.run_committed(d, nom, Path(spice_cases) if spice_cases else silicon.CASES_DIR,
                                           jobs=jobs or default_jobs())
    emit(r, as_json, lambda x: "\n".join(_selftest_text(k, v) for k, v in x.items()))


def _pct(v):
    return "n/a" if v is None else f"{v * 100:.1f} %"


def _selftest_text(kind, x):
    lines = [
        f"{x['kind']}: {x['n_cases']} blind cases ({x['n_effect_cases']} in-library, "
        f"{x['n_out_of_library_cases']} out-of-library, {x['n_clean_cases']} effect-free)"
        + (f", seeds {x['seeds'][0]} - {x['seeds'][1]}" if x.get("seeds") else ""),
        f"  top-1 {_pct(x['top1_accuracy'])}, explained when right {_pct(x['explained_when_right'])}, "
        f"median shrink {_pct(x['median_shrink'])}",
        f"  'not explained' on out-of-library {_pct(x['not_explained_on_out_of_library'])}, "
        f"none on effect-free {_pct(x['none_on_clean'])}",
        "  per effect: " + ", ".join(f"{k} {_pct(v)}" for k, v in x["per_effect_top1"].items())]
    if x.get("per_kind_explained"):
        lines.append("  explained per mechanism: " + ", ".join(f"{k} {_pct(v)}" for k, v in x["per_kind_explained"].items()))
    for k in ("uniform_named_uniform", "uniform_named_right", "uniform_visible_named_right", "mc_named_per_column",
              "two_effects_both_named", "dark_current_hot_named"):
        if x.get(k):
            lines.append(f"  {k.replace('_', ' ')}: {_pct(x[k]['rate'])} of {x[k]['n']}")
    return "\n".join(lines)


@gap.command()
@click.argument("design", type=FilePath(dir_okay=False), required=False, default=None)
@out_opt("folder for cases.csv and truth.json (default: the kit's pixelkit/gap/silicon_cases for the thesis read, "
         "whose cases the kit commits; reports/<design>/silicon_cases for any other design)", folder=True)
@spice_opts
@json_opt
def silicon(design, out, backend, jobs, as_json):
    """Make DESIGN's virtual-silicon SPICE cases (effects inserted as circuit elements; default DESIGN: the thesis
    read); slow: ~1000 decks."""
    from ..gap import silicon as si
    from ..gap.store import load_nominal
    from ..progress import progress, step
    d = load(design or THESIS_READ)
    if out is None and d.name != CASES_OF:   # never over the kit's committed cases of another design
        out = output_path(None, d, "silicon_cases")
    with step("building the SPICE-calibrated surrogate (first run only)"):
        nom = load_nominal(d, backend=backend)
    plan_ = si.plan_cases()
    bar = progress(total=len(plan_), desc="SPICE cases", unit="case")
    r = si.write_cases(d, nom, Path(out) if out else si.CASES_DIR, plan_, progress=lambda k, n: bar.update(1),
                       jobs=jobs)
    bar.close()
    emit(r, as_json, lambda x: f"wrote {x['n_cases']} cases to {x['folder']}")


@gap.command()
@design_arg
@out_opt("surrogate file (default: the kit's pixelkit/gap/surrogates/<design>.json)")
@spice_opts
@json_opt
def surrogate(design, out, backend, jobs, as_json):
    """Build the design's SPICE-calibrated surrogate from SPICE (a few hundred decks) and store it with its decks' key."""
    from ..gap import store
    from ..gap.nominal import build_nominal
    from ..progress import step
    d = load(design)
    with step("building the SPICE-calibrated surrogate"):
        nom = build_nominal(d, backend=backend)
    path = store.write(d, nom, Path(out) if out else None)
    emit({"out": str(path), "error_V": nom.error}, as_json, lambda x: f"wrote {x['out']}")


@gap.command()
@click.argument("dataset", type=FilePath(exists=True))
@json_opt
def emva(dataset, as_json):
    """EMVA 1288 figures of a dataset (any bit depth) and its camera-level gap: where, which, how far."""
    from ..gap.emva import analyse
    r = analyse(dataset)
    emit(r, as_json, _emva_text)


def _g(v, fmt):
    return "n/a" if v is None else format(v, fmt)


def _emva_text(x):
    f = x["figures"]
    lines = [f"verdict: {x['verdict']}"]
    if x.get("design_note"):
        lines.append(f"  ({x['design_note']})")
    lines += [f"EMVA 1288 ({f['bits']} bit, exposure in {f['exposure_unit']}): K = {f['K_DN_per_e']:.5g} DN/e-, "
             f"QE = {f['QE_percent']:.1f} %, sigma_d = {f['sigma_d_e']:.3g} e-, saturation {f['u_e_sat']:.0f} e-, "
             f"SNR_max {f['SNR_max_dB']:.1f} dB, DR {f['DR_dB']:.1f} dB, LE {f['LE_min_percent']:+.2f} / "
             f"{f['LE_max_percent']:+.2f} %",
             f"  dark current: {_g(f['dark_current_mean_e_per_s'], '.4g')} e-/s from the mean, "
             f"{_g(f['dark_current_var_e_per_s'], '.4g')} e-/s from the variance"
             + (f"; DSNU {_g(f['DSNU_e'], '.3g')} e-, PRNU {_g(f['PRNU_percent'], '.3g')} %" if "DSNU_e" in f else "")]
    if x["dark_noise"]:
        lines.append(f"  {x['dark_noise']['effect']}: {x['dark_noise']['text']}")
    lines += [f"  {w['region']:<26} n={w['n']:<3} mean residual {w['mean_resid_DN']:+.3f} DN, "
              f"variance {w['var_resid_rel'] * 100:+.1f} % vs PTC" for w in x["where"]]
    lines += [f"  {c['effect']:<16} held-out rms {c['heldout_rms_DN']:.3f} DN, chi2/step {c['heldout_chi2_per_row']:9.1f}"
              f"{'   beats none' if c['beats_none'] else ''}" for c in x["ranking"]]
    lines.append(f"best: {x['best']} (held-out gap {x['gap_before_rms_DN']:.3f} -> {x['gap_after_rms_DN']:.3f} DN, "
                 f"shrink {x['shrink_frac'] * 100:.0f} %; noise {x['noise_rms_DN']:.3f} DN: {x['noise_source']})")
    return "\n".join(lines)
