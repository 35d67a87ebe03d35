"""``pixelkit models | simulate | run``: the analytic table and the thesis [Thesis2019] experiment."""
from __future__ import annotations

import click

from .common import design_arg, emit, json_opt, load, main, spice_opts, waveforms_opt, post_layout_opt


@main.command()
@design_arg
@post_layout_opt
@json_opt
def models(design, as_json):
    """Analytic model table: C_jdep, conversion gain, full well, C_A, C_C."""
    from ..api import models as model_table
    from ..family import DEFAULT, family_models, family_of, family_text
    from ..report.text import model_text
    fam = family_of(design)
    if fam != DEFAULT:  # another pixel family: its closed-form figures
        return emit(family_models(design, fam), as_json, family_text)
    emit(model_table(load(design)), as_json, model_text)


def _waveforms(d, result, path, backend):
    """Simulate the dual-pixel bench at the experiment's operating point and write its waveforms."""
    from ..api import bench, simulate, write_waveforms
    net = bench(d, "bench_dual_pixel", i_primary=result["primary"]["i_mid_A"],
                i_secondary=result["secondary"]["i_5pct_A"])
    return str(write_waveforms(simulate(net, backend=backend), path))


@main.command()
@design_arg
@spice_opts
@waveforms_opt
@post_layout_opt
@json_opt
def simulate(design, backend, jobs, waveforms, as_json):
    """The simulation experiment of [Thesis2019] (fig. A.1 - A.3): i_mid, i_5pct, model vs SPICE.

    --waveforms writes the dual-pixel bench at (i_mid, i_5pct).
    """
    from ..api import experiment
    from ..experiments.reference import is_reference
    from ..family import DEFAULT, ROLE_FAMILIES, family_of, family_text, family_waveforms, run_family, run_loaded
    from ..report.text import simulate_text
    fam = family_of(design)
    if fam in ROLE_FAMILIES:   # a pixel read by role; with --post-layout the 4T's drawn cell's extraction
        from .common import load_role
        d = load_role(design, fam, "simulate")
        r = run_loaded(d, fam, backend=backend, jobs=jobs)
        if getattr(d, "post_layout", None) is not None:
            r["view"] = d.post_layout.source
        if waveforms:
            r["waveforms"] = family_waveforms(design, fam, waveforms, backend, design=d)
        return emit(r, as_json, family_text)
    if fam != DEFAULT:  # another pixel family (pixelkit/family.py): its own experiment
        r = run_family(design, fam, backend=backend, jobs=jobs)
        if waveforms:
            r["waveforms"] = family_waveforms(design, fam, waveforms, backend)
        return emit(r, as_json, family_text)
    d = load(design)
    r = experiment(d, backend=backend, jobs=jobs)
    if waveforms:
        r["waveforms"] = _waveforms(d, r, waveforms, backend)
    ref = is_reference(d)
    emit(r, as_json, lambda x: simulate_text(x, ref) + (f"\nwaveforms: {x['waveforms']}" if waveforms else ""))


@main.command()
@design_arg
@spice_opts
@waveforms_opt
@post_layout_opt
@json_opt
def run(design, backend, jobs, waveforms, as_json):
    """The main job on a design: model table and simulation summary."""
    from ..api import experiment, models as model_table
    from ..experiments.reference import is_reference
    from ..report.text import model_text, simulate_text
    d = load(design)
    r = {"models": model_table(d), "simulate": experiment(d, backend=backend, jobs=jobs)}
    if waveforms:
        r["waveforms"] = _waveforms(d, r["simulate"], waveforms, backend)
    ref = is_reference(d)
    emit(r, as_json, lambda x: "\n".join([model_text(x["models"]), "", simulate_text(x["simulate"], ref)]
                                         + ([f"waveforms: {x['waveforms']}"] if waveforms else [])))
