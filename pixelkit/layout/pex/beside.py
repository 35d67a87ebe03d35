"""A computation run in a forked process beside the caller's own, on a machine with a core to spare.

The extraction's far field (``farfield.first_order``) does not depend on the 2.5D terms, which the
caller computes meanwhile: on the 2 x 2 chip with its AFEs each is about half of the extraction's CPU
(``benchmarks/layout.py``). A fork shares the geometry (KLayout regions, which do not pickle) without
copying it; only the result (a dict of floats) comes back through a pipe. Where there is one core, the
geometry is small (the fork's cost is then a fair part of the work) or the child fails (killed, out of
memory) or the caller has other threads than the sign-off's deck waiters (a fork copies only the calling
thread: a lock another one holds would stay held in the child), the same function runs in the caller's process: the result is the same
either way.
"""
from __future__ import annotations

import os

#: below this the far field takes < ~0.2 s of CPU: not worth a process (DUALPIX, 157 polygons: 0.23 s of its
#: 1.0 s extraction; DUALPIX_COL, 377: 0.61 of 2.1 s, off the sign-off's critical path since session 7)
MIN_POLYGONS = 150
#: threads that only wait on a child process (``signoff.foundry.Job``: blocked in waitpid, holding nothing
#: the fork's child uses): a fork beside them is safe
WAITERS = "pixelkit-wait"


def beside(fn, size: int, *args):
    """Start ``fn(*args)`` in a forked child when there is a core to spare and ``size`` (polygons) is at least
    MIN_POLYGONS; a function returning its result (from the child, or computed here when there was none)."""
    import multiprocessing as mp
    import threading
    if ((os.cpu_count() or 1) < 2 or size < MIN_POLYGONS or "fork" not in mp.get_all_start_methods()
            or any(t is not threading.current_thread() and not t.name.startswith(WAITERS)
                   for t in threading.enumerate())):     # a fork of a threaded process may inherit a held lock
        return _Here(fn, args)
    ctx = mp.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)

    def run():
        try:
            send.send(fn(*args))
        finally:
            send.close()
    child = ctx.Process(target=run, daemon=True)
    child.start()
    send.close()

    return _Result(fn, args, recv, child)


class _Here:
    """``fn(*args)`` computed here when called."""

    def __init__(self, fn, args):
        self.fn, self.args = fn, args

    def __call__(self):
        return self.fn(*self.args)

    def cancel(self) -> None:
        pass


class _Result:
    """The child's answer when called (computed here when the child gave none); ``cancel`` ends the child."""

    def __init__(self, fn, args, recv, child):
        self.fn, self.args, self.recv, self.child = fn, args, recv, child

    def __call__(self):
        try:
            value = self.recv.recv()
        except EOFError:                 # the child died without an answer: compute it here
            value = self.fn(*self.args)
        finally:
            self.cancel()
        return value

    def cancel(self) -> None:
        self.recv.close()
        if self.child.is_alive():
            self.child.terminate()
        self.child.join()
