"""Count a command's SPICE runs (done of total, cache hits) and show them as its progress.

A :class:`SpiceCounter` is an observer of the engine (:func:`pixelkit.spice.engine.observe`):
every deck served from the cache, handed to ngspice (retries included) or finished is
counted, whichever backend and thread runs it. :func:`spice_progress` is the command-level
bar of a command whose work is SPICE runs it cannot count in advance (``array``, ``mc``,
``camera``, ``size``): its total grows as decks are queued.
"""
from __future__ import annotations

import threading
from contextlib import ExitStack, contextmanager


class SpiceCounter:
    def __init__(self, show):
        self.show = show
        self.runs = self.cached = self.done = self.total = 0
        self._lock = threading.Lock()
        self._stack = ExitStack()

    def _event(self, event: str, n: int) -> None:
        with self._lock:
            if event == "cached":
                self.cached += n
                self.total += n
            elif event == "queued":
                self.total += n
            elif event == "finished":
                self.runs += n
            self.done = self.runs + self.cached
        self.show(self)

    def text(self) -> str:
        return f"SPICE {self.done}/{self.total} runs, {self.cached} from cache"

    def __enter__(self):
        from .engine import observe
        self._stack.enter_context(observe(self._event))
        return self

    def __exit__(self, *exc):
        self._stack.close()
        return False


@contextmanager
def spice_progress(desc: str):
    """The command's one bar, counting its SPICE runs (cached ones included)."""
    from ..progress import command_bar
    with command_bar(desc, total=None, unit="runs") as bar:
        def show(c: SpiceCounter) -> None:
            bar.total = c.total
            bar.n = c.done
            bar.set_postfix_str(f"{c.cached} from cache", refresh=True)
        with SpiceCounter(show):
            yield bar
