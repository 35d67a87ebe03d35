"""Scratch folders for ngspice runs, and their end when the kit ends (however it ends).

Every run works in a folder the kit controls, under one root per main process
(``/tmp/pixelkit-<pid>-*``). A folder holds the kit's own ``.spiceinit`` (so no
``.spiceinit`` from the user's folder or home is read) and one link per model
folder (``models -> <technology's model folder>``), through which the deck
names its model files: no user path is ever written into deck text.

Lifetime: the root is removed at exit; if the main process is killed
(SIGKILL), a small watchdog process, which reads a pipe from the main process
and sees it close, removes the root; batch ngspice processes carry a
parent-death signal and shared-backend workers watch their parent and exit.
Roots left by a process that died before its watchdog could act (power loss)
are swept at the next start.

A run in flight is visible from outside: its folder holds a file ``running``
(the pid of the process that simulates: the batch ngspice, or the shared-backend
worker) from the moment ngspice starts until the run ends, so a test or a
monitor waits for ``/tmp/pixelkit-<pid>-*/*/running`` instead of guessing with
a sleep.
"""
from __future__ import annotations

import atexit
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from .. import owner

SPICEINIT = "set num_threads=1\n"
PREFIX = "pixelkit-"
_OWNER = "owner.pid"
_ROOT: Path | None = None
_LOCK = threading.Lock()
_WATCH = ("import os, shutil, sys, time\n"
          "sys.stdin.buffer.read()\n"  # returns when the main process has gone, however it went
          "for _ in range(20):\n"       # a dying worker may still write for a moment
          "    shutil.rmtree(sys.argv[1], ignore_errors=True)\n"
          "    time.sleep(0.3)\n"
          "    if not os.path.exists(sys.argv[1]):\n"
          "        break\n")


def root() -> Path:
    """This process tree's scratch root (made, watched and swept on first use)."""
    global _ROOT
    with _LOCK:
        if _ROOT is None:
            base = Path(tempfile.gettempdir())
            _sweep_stale(base)
            r = Path(tempfile.mkdtemp(prefix=f"{PREFIX}{os.getpid()}-", dir=base))
            (r / _OWNER).write_text(owner.tag())   # pid and start time (a reused pid is not the owner)
            _start_watchdog(r)
            atexit.register(shutil.rmtree, r, True)
            _ROOT = r
    return _ROOT


def adopt(path: str) -> None:
    """In a worker process: use the main process's root (the main process owns its lifetime)."""
    global _ROOT
    _ROOT = Path(path)


def _start_watchdog(r: Path) -> None:
    try:
        proc = subprocess.Popen([sys.executable, "-S", "-c", _WATCH, str(r)], stdin=subprocess.PIPE,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                start_new_session=True, close_fds=True)
    except OSError:
        return  # no watchdog: atexit and the next start's sweep still remove the root
    _start_watchdog.proc = proc  # the pipe stays open as long as this process lives


def _sweep_stale(base: Path) -> None:
    for d in base.glob(f"{PREFIX}*-*"):
        try:
            tag = (d / _OWNER).read_text(errors="replace").strip()
        except OSError:
            continue  # not a kit root (or not ours to judge)
        if not owner.alive(f"pk{tag}-0" if tag.isdigit() else tag):   # a bare pid: written by an older kit
            shutil.rmtree(d, ignore_errors=True)


def run_folder() -> Path:
    """A fresh folder for one batch run, with the kit's ``.spiceinit``."""
    d = Path(tempfile.mkdtemp(prefix="run-", dir=root()))
    (d / ".spiceinit").write_text(SPICEINIT)
    return d


def worker_folder() -> Path:
    """This worker's folder (made once, with the kit's ``.spiceinit``); the process works in it."""
    d = root() / f"worker-{os.getpid()}"
    if not d.is_dir():
        d.mkdir()
        (d / ".spiceinit").write_text(SPICEINIT)
    if Path.cwd() != d:
        os.chdir(d)
    return d


RUNNING = "running"


def mark_running(folder: Path, pid: int) -> None:
    """Say that ``pid`` simulates in ``folder`` now (written whole, so a reader never sees it
    empty). Only a signal for observers: a mark that cannot be written does not stop the run."""
    tmp = folder / f".{RUNNING}"
    try:
        tmp.write_text(str(pid))
        os.replace(tmp, folder / RUNNING)
    except OSError:
        pass


def clear_running(folder: Path) -> None:
    try:
        (folder / RUNNING).unlink()
    except FileNotFoundError:
        pass


def set_links(folder: Path, links: dict) -> None:
    """Make ``folder/<name> -> model folder`` for each link (replacing stale ones)."""
    for name, target in links.items():
        link = folder / name
        if link.is_symlink() and os.readlink(link) == str(target):
            continue
        if link.is_symlink() or link.exists():
            link.unlink()
        link.symlink_to(target, target_is_directory=True)


def watch_parent(parent: int, interval: float = 0.5) -> None:
    """In a worker: exit as soon as the main process ``parent`` is gone (it was killed),
    including when it died while this worker was still starting."""
    if os.getppid() != parent:
        os._exit(1)

    def loop():
        while True:
            time.sleep(interval)
            if os.getppid() != parent:
                os._exit(1)

    threading.Thread(target=loop, daemon=True, name="pixelkit-parent-watch").start()


def worker_init(path: str, parent: int) -> None:
    """Initializer of shared-backend worker processes (``parent``: the main process's pid)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the main process handles Ctrl-C and ends us
    adopt(path)
    watch_parent(parent)
