"""Batch backend: ``ngspice -b -r out.raw deck.cir`` in a scratch folder, raw file read back.

Each run gets its own folder (``scratch.run_folder``) holding the kit's
``.spiceinit`` - which sets ``num_threads=1`` (Debian's ngspice is built with
OpenMP and two parallel runs otherwise slow each other down by more than 10x,
measured with ngspice 39 on this kit's decks) and keeps any user ``.spiceinit`` from being read - and the
links to the model folders the deck names.
"""
from __future__ import annotations

import shutil
import subprocess
import threading
import time
from functools import lru_cache

from .. import children
from ..errors import PixelkitError
from . import scratch
from .raw import RawError, read_raw

_RUNNING: set = set()
_RUNNING_LOCK = threading.Lock()
_ABORTED = threading.Event()


@lru_cache(maxsize=1)
def ngspice_version() -> str:
    exe = shutil.which("ngspice")
    if exe is None:
        raise PixelkitError("ngspice is not installed: run ./setup.sh (Debian package 'ngspice')")
    out = subprocess.run([exe, "--version"], capture_output=True, text=True, timeout=30).stdout
    for tok in out.split():
        if tok.startswith("ngspice-"):
            return tok.split("-", 1)[1]
    return "unknown"


def abort_runs() -> None:
    """On an interrupt: kill every ngspice this process is running and start no new one."""
    with _RUNNING_LOCK:
        _ABORTED.set()
        procs = list(_RUNNING)
    for p in procs:
        try:
            p.kill()
        except OSError:
            pass


def run_batch(deck_text: str, links: dict | None = None,
              timeout: float = 600.0) -> tuple[list[dict], list[str], float]:
    """Run one deck; return (plots, output lines, wall seconds). No usable raw file: no plots.

    Whether the run succeeded is decided by the caller from the plots (engine._to_result).
    """
    ngspice_version()
    tmp = scratch.run_folder()
    try:
        scratch.set_links(tmp, links or {})
        (tmp / "deck.cir").write_text(deck_text)
        t0 = time.perf_counter()
        p = children.popen(["ngspice", "-b", "-r", "out.raw", "deck.cir"], cwd=tmp,   # dies with the kit
                           stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True, errors="replace")
        with _RUNNING_LOCK:
            _RUNNING.add(p)
            if _ABORTED.is_set():
                p.kill()
        try:
            scratch.mark_running(tmp, p.pid)  # the folder goes when the run ends, and the mark with it
            out, err = p.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            p.kill()
            p.communicate()
            return [], [f"ngspice did not finish within {timeout:g} s"], timeout
        finally:
            with _RUNNING_LOCK:
                _RUNNING.discard(p)
            children.forget(p)
        wall = time.perf_counter() - t0
        lines = (out + "\n" + err).splitlines()
        raw = tmp / "out.raw"
        plots = []
        if raw.exists() and raw.stat().st_size > 0:
            try:
                plots = read_raw(raw)
            except RawError as exc:
                lines.append(f"error: {exc}")
        if p.returncode != 0:
            lines.append(f"ngspice exited with status {p.returncode}")
        return plots, lines, wall
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
