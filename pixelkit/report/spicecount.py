"""Count the SPICE runs a report makes (done of total, cache hits) for the progress line.

A :class:`SpiceCounter` is an observer of the engine (:func:`pixelkit.spice.engine.observe`):
every deck served from the cache, handed to ngspice (retries included) or finished is
counted, whichever backend and thread runs it.
"""
from __future__ import annotations

import threading
from contextlib import ExitStack


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
        self.show(f"SPICE {self.done}/{self.total} runs, {self.cached} from cache")

    def __enter__(self):
        from ..spice.engine import observe
        self._stack.enter_context(observe(self._event))
        return self

    def __exit__(self, *exc):
        self._stack.close()
        return False
