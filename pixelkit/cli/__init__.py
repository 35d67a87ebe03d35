"""The ``pixelkit`` command line, one module per command group.

``common`` holds the click group, the shared options, output and the entry
point; every other module adds its commands to that group when imported. A new
command group is one module here and one name in ``COMMAND_MODULES``.
"""
from __future__ import annotations

import importlib

COMMAND_MODULES = ("simulate", "netlists", "array", "size", "layout", "gap", "report", "sensor", "camera", "sweep", "mc", "verify",
                   "close", "lightmap", "waves", "signoff")


def register_all() -> None:
    """Import every command module (each registers its commands on ``common.main``)."""
    for name in COMMAND_MODULES:
        importlib.import_module(f"{__name__}.{name}")


def entry(argv=None):
    """The command line: every command registered, then ``common.run`` (``argv``: in-process use;
    None: the console script, which also installs the Ctrl-C handler)."""
    register_all()
    from .common import run
    run(argv)
