"""Count the SPICE runs a report makes (done of total, cache hits) for the progress line.

The engine has no progress hook, so while a report builds this context manager
wraps the engine's own module-level functions (``_run`` for each batch of decks,
``run_batch`` for each finished deck, the cache's ``load`` for hits) and restores
them on exit. Nothing else changes: the wrapped functions are called as before.
"""
from __future__ import annotations

import threading


class SpiceCounter:
    def __init__(self, show):
        self.show = show
        self.runs = self.cached = self.done = self.total = 0
        self._lock = threading.Lock()
        self._saved = None

    def _tell(self):
        self.show(f"SPICE {self.done}/{self.total} runs, {self.cached} from cache")

    def __enter__(self):
        from ..spice import cache, engine
        run, run_batch, load = engine._run, engine.run_batch, cache.load
        self._saved = (run, run_batch, load)

        def counted_run(decks, *a, **k):
            with self._lock:
                self.total += len(decks)
            self._tell()
            out = run(decks, *a, **k)
            with self._lock:
                self.runs += len(decks)
                self.done = self.runs + self.cached
            self._tell()
            return out

        def counted_batch(*a, **k):
            out = run_batch(*a, **k)
            with self._lock:
                self.done += 1
            self._tell()
            return out

        def counted_load(key):
            r = load(key)
            if r is not None:
                with self._lock:
                    self.cached += 1
                    self.total += 1
                    self.done += 1
            return r

        engine._run, engine.run_batch, cache.load = counted_run, counted_batch, counted_load
        return self

    def __exit__(self, *exc):
        from ..spice import cache, engine
        engine._run, engine.run_batch, cache.load = self._saved
        return False
