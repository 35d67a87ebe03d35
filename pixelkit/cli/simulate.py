"""``pixelkit models | simulate | run``: the analytic table and the thesis experiment."""
from __future__ import annotations

import click

from .common import design_arg, emit, json_opt, main


@main.command()
@design_arg
@json_opt
def models(design, as_json):
    """Analytic model table: C_jdep, conversion gain, full well, C_A, C_C."""
    from ..design import load_design
    from ..physics.subpixel import model_table
    from ..report.text import model_text
    emit(model_table(load_design(design)), as_json, model_text)


@main.command()
@design_arg
@json_opt
@click.option("--backend", type=click.Choice(["batch", "shared"]), default="batch", show_default=True)
@click.option("--jobs", type=click.IntRange(1, 64), default=None, help="parallel ngspice workers")
def simulate(design, as_json, backend, jobs):
    """The thesis's simulation experiment: i_mid, i_5pct, model vs SPICE."""
    from ..design import load_design
    from ..experiments.thesis import run_experiment
    from ..report.text import simulate_text
    emit(run_experiment(load_design(design), backend=backend, jobs=jobs), as_json, simulate_text)


@main.command()
@design_arg
@click.option("--backend", type=click.Choice(["batch", "shared"]), default="batch", show_default=True)
def run(design, backend):
    """The main job on a design: model table and simulation summary."""
    from ..design import load_design
    from ..experiments.thesis import run_experiment
    from ..physics.subpixel import model_table
    from ..report.text import model_text, simulate_text
    d = load_design(design)
    click.echo(model_text(model_table(d)))
    click.echo("")
    click.echo(simulate_text(run_experiment(d, backend=backend)))
