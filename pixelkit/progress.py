"""Progress bars for anything that runs longer than a couple of seconds.

``progress(iterable, total=..., desc=...)`` wraps an iterable in a tqdm bar on
stderr. The bar is quiet (no output at all) when stderr is not a terminal, when
the command runs with ``--json`` (the CLI calls :func:`set_quiet`), or when the
environment sets ``PIXELKIT_PROGRESS=0``; ``PIXELKIT_PROGRESS=1`` forces it on.
Library code uses it freely: a script or a test that pipes stderr sees nothing.

``step(desc)`` is a context manager for one long step without an iterable (for
example a surrogate build): it shows an indeterminate bar while it runs.
"""
from __future__ import annotations

import os
import sys
from contextlib import contextmanager

_QUIET = False


def set_quiet(quiet: bool = True) -> None:
    """Silence (or re-enable) every progress bar of this process."""
    global _QUIET
    _QUIET = bool(quiet)


def enabled() -> bool:
    env = os.environ.get("PIXELKIT_PROGRESS", "")
    if env == "0" or _QUIET:
        return False
    if env == "1":
        return True
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


def progress(iterable=None, total: int | None = None, desc: str = "", unit: str = "run", **kw):
    """A tqdm bar over ``iterable`` (or a manual bar with ``total``), or a silent one."""
    from tqdm.auto import tqdm
    return tqdm(iterable, total=total, desc=desc, unit=unit, disable=not enabled(), leave=False,
                file=sys.stderr, dynamic_ncols=True, **kw)


@contextmanager
def step(desc: str):
    """An indeterminate bar for one long step; closes when the block ends."""
    import threading
    bar = progress(total=None, desc=desc, unit="s", bar_format="{desc}: {elapsed}")
    done = threading.Event()

    def tick():
        while not done.wait(0.5):
            bar.refresh()

    ticker = threading.Thread(target=tick, daemon=True)
    if not bar.disable:
        ticker.start()
    try:
        yield bar
    finally:
        done.set()
        bar.close()
