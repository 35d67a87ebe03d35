"""The external programs the kit runs (ngspice, KLayout) end with the kit, however it ends.

Every child process is started through :func:`popen` / :func:`run`, which give it a
parent-death signal: the kernel sends it SIGKILL the moment the kit's process goes, on
``kill -9`` too (``prctl(PR_SET_PDEATHSIG)``). It is set by ``setpriv --pdeathsig KILL``
(util-linux, part of every Debian) in front of the program, which then ``exec``s it - the
child keeps the same pid, and nothing runs in the forked child before ``exec`` (a
``preexec_fn`` is not safe while other threads run, and ngspice runs are started from
threads). Where ``setpriv`` is missing, a ``preexec_fn`` makes the same ``prctl`` call through
ctypes and ends the child at once if its parent has already gone.

Caveat of the mechanism: the signal follows the *thread* that started the child, so a child
must be waited for by the thread that started it (every caller here does: ``run`` returns
when the child has ended; ``popen`` callers call ``communicate``). Children of the child
(a shell a deck starts) are not covered; the decks the kit runs start none.

While running, a child is listed in :data:`RUNNING` (Ctrl-C: :func:`kill_all`). Shared-backend
ngspice workers (``spice.engine``) are Python processes of the kit's own and watch their parent
instead (``spice.scratch.watch_parent``).
"""
from __future__ import annotations

import os
import shutil
import signal
import subprocess
import threading
from functools import lru_cache

PR_SET_PDEATHSIG = 1
RUNNING: set = set()
_LOCK = threading.Lock()


@lru_cache(maxsize=1)
def _setpriv() -> str | None:
    exe = shutil.which("setpriv")
    if exe is None:
        return None
    try:   # an old util-linux has no --pdeathsig
        ok = subprocess.run([exe, "--pdeathsig", "KILL", "true"], capture_output=True, timeout=30).returncode == 0
    except (OSError, subprocess.SubprocessError):
        ok = False
    return exe if ok else None


def command(argv: list[str]) -> list[str]:
    """``argv`` wrapped so the child is killed when its parent dies (``setpriv --pdeathsig``),
    or as it is when the wrapper is missing (then :func:`popen` uses the ctypes fallback)."""
    exe = _setpriv()
    return [exe, "--pdeathsig", "KILL", *argv] if exe else list(argv)


def _die_with_parent(parent: int):
    def set_signal():   # runs in the forked child, before exec
        import ctypes
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        if os.getppid() != parent:   # the parent died before the call: nobody would send it
            os._exit(1)
    return set_signal


def popen(argv: list[str], **kw) -> subprocess.Popen:
    """``subprocess.Popen`` of ``argv`` with the parent-death signal set; listed in RUNNING until
    :func:`forget` (``run`` does both)."""
    wrapped = command(argv)
    if wrapped == list(argv) and "preexec_fn" not in kw:
        kw["preexec_fn"] = _die_with_parent(os.getpid())
    p = subprocess.Popen(wrapped, **kw)
    with _LOCK:
        RUNNING.add(p)
    return p


def forget(p: subprocess.Popen) -> None:
    with _LOCK:
        RUNNING.discard(p)


def run(argv: list[str], timeout: float | None = None, **kw) -> subprocess.CompletedProcess:
    """Run ``argv`` to its end (as ``subprocess.run``) with the parent-death signal; killed when
    the wait is interrupted (Ctrl-C, an exception, the timeout - then ``TimeoutExpired``)."""
    capture = kw.pop("capture_output", False)
    if capture:
        kw["stdout"], kw["stderr"] = subprocess.PIPE, subprocess.PIPE
    p = popen(argv, **kw)
    try:
        out, err = p.communicate(timeout=timeout)
    except BaseException:
        p.kill()
        p.wait()
        raise
    finally:
        forget(p)
    return subprocess.CompletedProcess(p.args, p.returncode, out, err)


def kill_all() -> None:
    """Kill every child this process is running (on an interrupt)."""
    with _LOCK:
        procs = list(RUNNING)
    for p in procs:
        try:
            p.kill()
        except OSError:
            pass
