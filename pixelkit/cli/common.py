"""The ``pixelkit`` command: the group, the shared options, output and ``run`` (errors, exit statuses).

The convention every command follows (docs/cli-conventions.md):

- the design file is the first positional argument (``design_arg``); commands
  that work on a design load it with :func:`load` (it prints the design's
  working-range warnings on stderr and adds them to the JSON output);
- ``--json`` (``json_opt``) on every command: the result is one JSON object on
  stdout, progress bars are silenced, and an error is one JSON object on stdout
  ``{"error", "field", "value", "allowed", "exit_status", ...}`` (and, as
  without ``--json``, one line ``pixelkit: error: ...`` on stderr);
- one output option, ``--out`` (``out_opt``): a file or a folder, depending on
  the command. Without it, outputs go under ``reports/<design>/`` of the current
  folder (``$PIXELKIT_REPORTS`` replaces ``reports``), see :func:`output_path`;
  never beside the design file;
- ``--jobs`` / ``--backend`` (``spice_opts``) on every command that runs SPICE,
  and ``--waveforms FILE`` (``waveforms_opt``; ``.csv``, or ngspice raw when the
  name ends in ``.raw``) on those that can hand back a waveform;
- exit statuses (``pixelkit.errors``): 0 ok, 1 regression / difference found,
  2 user error, 3 internal fault, 4 simulation failed, 5 nothing failed but something
  asked was not measured (``errors.verdict_exit`` decides a verdict's status), 130 interrupted. Raise
  :class:`~pixelkit.errors.RegressionFound` (or call ``sys.exit(1)`` after
  emitting) for a difference, ``ConfigError``/``PixelkitError`` for bad input;
  never ``sys.exit(2)`` by hand;
- anything that runs longer than a couple of seconds shows its progress on stderr
  (:mod:`pixelkit.progress`: a bar on a terminal, plain lines otherwise, one per command
  - :func:`~pixelkit.progress.command_bar`, or ``spice.counter.spice_progress`` to count
  SPICE runs); ``--quiet`` (in ``spice_opts``) and ``--json`` silence it.

How to add a command group ``foo``:

1. create ``pixelkit/cli/foo.py``::

       import click
       from .common import design_arg, emit, json_opt, load, main, out_opt, output_path, spice_opts

       @main.command()
       @design_arg
       @out_opt("where the foo table goes (default reports/<design>/foo.csv)")
       @spice_opts
       @json_opt
       def foo(design, out, backend, jobs, as_json):
           \"\"\"One line that says what foo does (shown by ``pixelkit -h``).\"\"\"
           from ..foo import run_foo          # heavy imports inside the command
           d = load(design)
           path = output_path(out, d, "foo.csv")
           r = run_foo(d, path, backend=backend, jobs=jobs)   # the API does the work
           emit(r, as_json, lambda x: f"wrote {x['path']}")

   (use ``@main.group()`` for a group with subcommands, as ``gap.py`` does);
2. append ``"foo"`` to ``COMMAND_MODULES`` in ``pixelkit/cli/__init__.py``;
3. add the command to the README's Commands table and a test that runs it with
   ``--json`` (``tests/test_cli_conventions.py`` checks every command has it).
"""
from __future__ import annotations

import json
import os
import sys
import traceback
from pathlib import Path

import click

from .types import FilePath

from ..errors import EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_USER, PixelkitError
from ..fileio import json_default

#: Warnings raised while this command ran (working range, ...); ``emit`` adds them to JSON.
WARNINGS: list[str] = []


def emit(data: dict, as_json: bool, render) -> None:
    """Print ``data`` as one JSON object, or as the human-readable text of ``render``."""
    from ..finite import refuse_nonfinite
    refuse_nonfinite(data)  # issue 9: no NaN / Infinity printed as a figure
    if as_json:
        if WARNINGS and isinstance(data, dict) and "warnings" not in data:
            data = {**data, "warnings": list(WARNINGS)}
        click.echo(json.dumps(data, indent=1, default=json_default))
    else:
        click.echo(render(data))


def warn(message: str) -> None:
    """A warning for the user: one line on stderr, and in the JSON output."""
    WARNINGS.append(message)
    click.echo(f"pixelkit: warning: {message}", err=True)


def _quiet(ctx, param, value):
    if value:
        from ..progress import set_quiet
        set_quiet(True)
    return value


design_arg = click.argument("design", type=FilePath(dir_okay=False))
json_opt = click.option("--json", "as_json", is_flag=True, callback=_quiet,
                        help="print one JSON object (errors too); no progress bars")
quiet_opt = click.option("--quiet", is_flag=True, callback=_quiet, expose_value=False,
                         help="no progress on stderr (a bar on a terminal, plain lines otherwise)")


def out_checked(folder: bool):
    def check(ctx, param, value):
        ctx.meta["pixelkit.out_folder"] = folder
        if value is not None:   # a device, a file for a folder, a link to nothing: refused before any work
            from ..fileio import check_output
            check_output(Path(value), folder=folder)
        return value
    return check


def out_opt(help_text: str, folder: bool = False):
    """The one output option, ``--out`` (a file, or a folder with ``folder=True``), checked when
    the command line is read (:func:`pixelkit.fileio.check_output`)."""
    kind = FilePath(file_okay=False) if folder else FilePath(dir_okay=False)
    return click.option("--out", type=kind, default=None, help=help_text, callback=out_checked(folder))


def _waveforms_checked(ctx, param, value):
    """``--waveforms FILE``: a file in a folder that exists (the kit makes no folder for one file,
    issue 44), its place free or a regular file; checked before anything is simulated."""
    if value is None:
        return None
    from ..errors import ConfigError
    from ..fileio import check_output, path_kind
    parent = Path(value).parent
    if path_kind(parent) != "dir":
        raise ConfigError("command line", "--waveforms", value, f"a file in an existing folder ({parent} is not one)")
    check_output(Path(value), folder=False)
    return value


def _jobs(ctx, param, value):
    if value:  # the process-wide default of every SPICE run of this command (spice.engine.default_jobs)
        os.environ["PIXELKIT_JOBS"] = str(value)
    return value


def spice_opts(f):
    """``--backend``, ``--jobs`` and ``--quiet``, for every command that runs SPICE."""
    f = quiet_opt(f)
    f = click.option("--jobs", type=click.IntRange(1, 64), default=None, callback=_jobs,
                     help="parallel ngspice workers (default: $PIXELKIT_JOBS, else the cores, at most 8)")(f)
    return click.option("--backend", type=click.Choice(["batch", "shared"]), default="batch",
                        show_default=True, help="ngspice as a process per deck, or the shared library")(f)


def scheduler_address(ctx, param, value):
    """Callback of every ``--scheduler`` option: the address checked before anything runs."""
    if value is None:
        return None
    from ..spice.executors import check_address
    return check_address(value)


waveforms_opt = click.option("--waveforms", type=FilePath(dir_okay=False), default=None,
                             callback=_waveforms_checked,
                             help="write the simulated waveforms: CSV (time_s, v(node)_V, ...) "
                                  "or ngspice raw when the name ends in .raw")


def output_path(out, design, default_name: str) -> Path:
    """``--out`` if given, else ``reports/<design name>/<default_name>``."""
    from ..fileio import check_output, reports_root
    ctx = click.get_current_context(silent=True)
    folder = None if ctx is None else ctx.meta.get("pixelkit.out_folder")
    if out:
        return check_output(Path(out), folder=folder)
    name = design if isinstance(design, str) else design.name
    return check_output(reports_root() / name / default_name, folder=folder)


def _post_layout(ctx, param, value):
    if value:
        ctx.meta["pixelkit.post_layout"] = True
    return value


post_layout_opt = click.option("--post-layout", is_flag=True, expose_value=False, callback=_post_layout,
                               help="run on the post-layout view: the wiring parasitics extracted from the "
                                    "design's own layout (docs/post-layout.md)")


def load(design_path: str, drawable: bool = True, afe: bool = True):
    """Load a design for a command: warnings on stderr (and in the JSON output)
    (``drawable=False``: no warning that the layout cannot be drawn - ``layout`` says it as an error);
    with ``--post-layout`` the post-layout view (a technology without a stack is refused, naming it;
    ``afe=False``: a command that simulates no AFE, the view extracted without them)."""
    from ..api import load_design
    return view(load_design(design_path, warn=warn, drawable=drawable), afe)


def refuse_post_layout(command: str, family: str) -> None:
    """A netlist pixel has no post-layout view (its layout is the designer's): ``--post-layout`` is refused
    (exit 2) rather than ignored."""
    ctx = click.get_current_context(silent=True)
    if ctx is not None and ctx.meta.get("pixelkit.post_layout"):
        from ..errors import ConfigError
        raise ConfigError(command, "--post-layout", True, f"a dual-pixel design or a 4T for this command (a {family} "
                          "design has no post-layout view yet: sign off your own GDS with pixelkit signoff: its "
                          "post-layout netlist is <top>.post.spice)")


def load_role(path, family: str, command: str):
    """A design read by role, for ``command``: with ``--post-layout`` the 4T's post-layout view (its drawn
    cell's extraction in its subcircuit, ``layout.pixel4t``); a netlist pixel's is refused (exit 2)."""
    from ..family import load_family_design
    ctx = click.get_current_context(silent=True)
    if ctx is not None and ctx.meta.get("pixelkit.post_layout") and family != "pixel4t":
        refuse_post_layout(command, family)
    d = load_family_design(path, family)
    if ctx is not None and ctx.meta.get("pixelkit.post_layout"):
        from ..layout.pixel4t import post_layout_view
        return post_layout_view(d)
    return d


def view(design, afe: bool = True):
    """``design`` as the command asked: its post-layout view with ``--post-layout`` (with the AFEs'
    extraction unless ``afe`` is False), else as loaded."""
    ctx = click.get_current_context(silent=True)
    if ctx is not None and ctx.meta.get("pixelkit.post_layout"):
        from ..layout.pex.overlay import post_layout_view
        return post_layout_view(design, afe)
    return design


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="pixelkit")
def main():
    """pixelkit: circuit-level CMOS image-sensor pixel and readout design kit.

    Exit status: 0 ok, 1 difference found, 2 user error, 3 internal fault,
    4 simulation failed, 5 not everything asked was measured, 130 interrupted. Outputs: --out, else reports/<design>/.
    """


def _fail(as_json: bool, status: int, message: str, details: dict | None = None) -> None:
    if as_json:
        obj = {"error": message, "field": None, "value": None, "allowed": None, **(details or {}),
               "exit_status": status}
        if WARNINGS:
            obj["warnings"] = list(WARNINGS)
        click.echo(json.dumps(obj, indent=1, default=json_default))
    click.echo(f"pixelkit: error: {message}", err=True)  # the one line for a person, JSON or not
    sys.exit(status)


class Interrupted(BaseException):
    """Ctrl-C, raised by our SIGINT handler (click turns KeyboardInterrupt into a blank line + Abort)."""


_INTERRUPT = {"said": False, "count": 0}


def _on_sigint(_signum, _frame):
    """Raise :class:`Interrupted`; if the clean shutdown hangs (a lock held by the interrupted
    code) or Ctrl-C comes again, end hard after a moment with the same line and status."""
    import threading
    _INTERRUPT["count"] += 1

    def hard_exit():
        if not _INTERRUPT["said"]:
            sys.stderr.write("pixelkit: error: interrupted\n")
        sys.stderr.flush()
        os._exit(EXIT_INTERRUPTED)

    if _INTERRUPT["count"] > 1:
        hard_exit()
    timer = threading.Timer(3.0, hard_exit)
    timer.daemon = True
    timer.start()
    raise Interrupted()


def _one_line_warning(message, category, filename, lineno, line=None) -> str:
    """How a warning that reached the user reads: one line, no source file or line of the kit."""
    module = "numpy" if "numpy" in filename else "scipy" if "scipy" in filename else Path(filename).stem
    text = " ".join(str(message).split())
    WARNINGS.append(f"{category.__name__} ({module}): {text}")
    return f"pixelkit: warning: {category.__name__} ({module}): {text}\n"


def finishing() -> None:
    """The command has computed everything; what is left is writing its output and the summary
    (milliseconds). Ctrl-C from here on is ignored, so a finished run is never reported as
    interrupted; before this call an interrupt leaves no output (the writers are atomic). Only
    where the console script installed its handler (a caller's own Ctrl-C is left alone)."""
    import signal
    import threading
    if threading.current_thread() is threading.main_thread() and signal.getsignal(signal.SIGINT) is _on_sigint:
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def run(argv=None):
    """Run the registered commands (``pixelkit.cli.entry`` registers them first): one-line (or JSON)
    errors with distinct exit statuses, no tracebacks."""
    import signal
    args = list(sys.argv[1:] if argv is None else argv)
    as_json = "--json" in args
    if argv is None:  # the console script: Ctrl-C ends with one line and status 130
        signal.signal(signal.SIGINT, _on_sigint)
    import warnings
    warnings.formatwarning = _one_line_warning   # a library's warning never shows the kit's source lines
    try:
        main(args=args, standalone_mode=False)
    except Interrupted:
        _INTERRUPT["said"] = True
        _fail(as_json, EXIT_INTERRUPTED, "interrupted")
    except click.exceptions.Exit as exc:
        sys.exit(exc.exit_code)
    except click.exceptions.Abort:
        _fail(as_json, EXIT_INTERRUPTED, "interrupted")
    except click.ClickException as exc:
        details = {}
        if isinstance(exc, click.BadParameter) and exc.param is not None:
            details = {"field": exc.param.opts[0] if exc.param.opts else exc.param.name}
        if as_json:
            _fail(as_json, EXIT_USER, exc.format_message(), details)
        exc.show()
        sys.exit(EXIT_USER)
    except PixelkitError as exc:
        _fail(as_json, exc.exit_status, str(exc), exc.details())
    except KeyboardInterrupt:
        _fail(as_json, EXIT_INTERRUPTED, "interrupted")
    except Exception as exc:  # an internal fault: say so plainly
        if os.environ.get("PIXELKIT_DEBUG"):
            traceback.print_exc()
        _fail(as_json, EXIT_INTERNAL, f"internal error ({type(exc).__name__}: {exc}); "
              "set PIXELKIT_DEBUG=1 for the traceback and please report it")
