"""Batch backend: ``ngspice -b -r out.raw deck.cir`` in a scratch folder, raw file read back.

Each run gets its own folder with a ``.spiceinit`` that sets ``num_threads=1``:
Debian's ngspice is built with OpenMP and two parallel runs otherwise slow each
other down by more than 10x (NGSPICE_NOTES.md).
"""
from __future__ import annotations

import shutil
import subprocess
import tempfile
import time
from functools import lru_cache
from pathlib import Path

from ..errors import PixelkitError
from .raw import read_raw

SPICEINIT = "set num_threads=1\n"


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


def run_batch(deck_text: str, timeout: float = 600.0) -> tuple[list[dict], list[str], float]:
    """Run one deck; return (plots, output lines, wall seconds). No raw file: no plots.

    Whether the run succeeded is decided by the caller from the plots (engine._to_result).
    """
    ngspice_version()
    with tempfile.TemporaryDirectory(prefix="pixelkit-") as tmp:
        tmp = Path(tmp)
        (tmp / ".spiceinit").write_text(SPICEINIT)
        (tmp / "deck.cir").write_text(deck_text)
        t0 = time.perf_counter()
        try:
            p = subprocess.run(["ngspice", "-b", "-r", "out.raw", "deck.cir"], cwd=tmp,
                               capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return [], [f"ngspice did not finish within {timeout:g} s"], timeout
        wall = time.perf_counter() - t0
        lines = (p.stdout + "\n" + p.stderr).splitlines()
        raw = tmp / "out.raw"
        plots = read_raw(raw) if raw.exists() and raw.stat().st_size > 0 else []
        if p.returncode != 0:
            lines.append(f"ngspice exited with status {p.returncode}")
        return plots, lines, wall
