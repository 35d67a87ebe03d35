"""The ``pixelkit`` command line, one module per command group.

``common`` holds the click group, the shared options, output and the entry
point; every other module adds its commands to that group when imported. A new
command group is one module here and one name in ``COMMAND_MODULES``.
"""
from __future__ import annotations

import importlib

COMMAND_MODULES = ("simulate", "netlists", "array", "size", "layout", "gap", "report", "sensor", "camera", "sweep", "mc")


def register_all() -> None:
    """Import every command module (each registers its commands on ``common.main``)."""
    for name in COMMAND_MODULES:
        importlib.import_module(f"{__name__}.{name}")


def entry():
    from .common import entry as _entry
    _entry()
