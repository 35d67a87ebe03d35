"""The ``pixelkit`` click group with every command registered, for the site's CLI reference
(``docs/cli.md``: mkdocs-click reads ``main`` here)."""
from pixelkit.cli import register_all
from pixelkit.cli.common import main

register_all()

__all__ = ["main"]
