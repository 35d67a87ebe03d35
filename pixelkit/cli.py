"""The ``pixelkit`` command.

Every subcommand that produces figures takes ``--json`` and then prints one
JSON object on stdout. Errors a user can fix print one line on stderr and exit
with status 2; a regression that found changes exits with status 1.
"""
from __future__ import annotations

import json
import os
import sys
import traceback

import click

from .errors import PixelkitError


def emit(data: dict, as_json: bool, render) -> None:
    """Print ``data`` as one JSON object, or as the human-readable text of ``render``."""
    if as_json:
        click.echo(json.dumps(data, indent=1, default=_jsonable))
    else:
        click.echo(render(data))


def _jsonable(x):
    import numpy as np
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    return str(x)


design_arg = click.argument("design", type=click.Path(dir_okay=False))
json_opt = click.option("--json", "as_json", is_flag=True, help="print one JSON object")


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="pixelkit")
def main():
    """pixelkit: circuit-level CMOS image-sensor pixel and readout design kit."""


@main.command()
@design_arg
@json_opt
def models(design, as_json):
    """Analytic model table: C_jdep, conversion gain, full well, C_A, C_C."""
    from .design import load_design
    from .physics.subpixel import model_table
    from .report.text import model_text
    emit(model_table(load_design(design)), as_json, model_text)


@main.command()
@design_arg
@json_opt
@click.option("--backend", type=click.Choice(["batch", "shared"]), default="batch", show_default=True)
@click.option("--jobs", type=click.IntRange(1, 64), default=None, help="parallel ngspice workers")
def simulate(design, as_json, backend, jobs):
    """The thesis's simulation experiment: i_mid, i_5pct, model vs SPICE."""
    from .design import load_design
    from .experiments.thesis import run_experiment
    from .report.text import simulate_text
    emit(run_experiment(load_design(design), backend=backend, jobs=jobs), as_json, simulate_text)


@main.command()
@design_arg
@click.option("--backend", type=click.Choice(["batch", "shared"]), default="batch", show_default=True)
def run(design, backend):
    """The main job on a design: model table and simulation summary."""
    from .design import load_design
    from .experiments.thesis import run_experiment
    from .physics.subpixel import model_table
    from .report.text import model_text, simulate_text
    d = load_design(design)
    click.echo(model_text(model_table(d)))
    click.echo("")
    click.echo(simulate_text(run_experiment(d, backend=backend)))


def _register_optional():
    """Subcommands that live in their own modules (each adds itself to ``main``)."""
    from . import cli_more  # noqa: F401  (registers netlists, regress, array, size, layout)
    from .gap import cli as gap_cli  # noqa: F401  (registers gap)


def entry():
    """Console entry point: one-line errors, no tracebacks for user mistakes."""
    _register_optional()
    try:
        main(standalone_mode=False)
    except click.exceptions.Exit as exc:
        sys.exit(exc.exit_code)
    except click.ClickException as exc:
        exc.show()
        sys.exit(2)
    except click.exceptions.Abort:
        click.echo("aborted", err=True)
        sys.exit(130)
    except PixelkitError as exc:
        click.echo(f"pixelkit: error: {exc}", err=True)
        sys.exit(2)
    except KeyboardInterrupt:
        sys.exit(130)
    except Exception as exc:  # an internal fault: say so plainly
        if os.environ.get("PIXELKIT_DEBUG"):
            traceback.print_exc()
        click.echo(f"pixelkit: internal error ({type(exc).__name__}: {exc}); "
                   "set PIXELKIT_DEBUG=1 for the traceback and please report it", err=True)
        sys.exit(3)
