"""The ``pixelkit`` command: the group, shared options, output and the entry point.

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

from ..errors import PixelkitError


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


def entry():
    """Console entry point: one-line errors, no tracebacks for user mistakes."""
    from . import register_all
    register_all()
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
