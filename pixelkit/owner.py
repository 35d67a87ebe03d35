"""Who owns a temporary file or folder, and removing those whose owner is gone.

Every temporary the kit leaves beside an output or in a cache while it works (a file
being written, a report's staging folder, a cache entry being saved, a scratch root)
carries its owner's tag in its name: ``pk<pid>-<start>``, the process id and the
process's start time (clock ticks since boot, from ``/proc/<pid>/stat``), so a reused
process id is not mistaken for the owner. A run killed with SIGKILL cannot remove its own
temporaries; the next run that meets them does (:func:`sweep`) when their owner is no
longer running, so a kill at any moment leaves at most one run's debris, never a pile.
"""
from __future__ import annotations

import os
import re
import shutil
from functools import lru_cache
from pathlib import Path

TAG = re.compile(r"pk(\d+)-(\d+)")


def _start_ticks(pid: int) -> int | None:
    """The start time of process ``pid`` (clock ticks since boot), or None when it is not running."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            stat = fh.read()
    except FileNotFoundError:
        return None
    except OSError:
        return 0   # no /proc: the start time is unknown, the pid alone decides
    try:
        return int(stat.rsplit(b")", 1)[1].split()[19])
    except (IndexError, ValueError):
        return 0


@lru_cache(maxsize=1)
def _my_tag(pid: int) -> str:
    return f"pk{pid}-{_start_ticks(pid) or 0}"


def tag() -> str:
    """This process's owner tag (``pk<pid>-<start>``)."""
    return _my_tag(os.getpid())


def alive(owner: str) -> bool:
    """True when the process named by the tag ``owner`` is still running (the same process)."""
    m = TAG.fullmatch(owner)
    if not m:
        return True   # not a tag of ours: never removed
    pid, start = int(m.group(1)), int(m.group(2))
    now = _start_ticks(pid)
    if now is None:
        return False
    if now and start and now != start:
        return False   # the pid was reused by another process
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def owner_of(name: str) -> str | None:
    """The owner tag inside a temporary's name, or None."""
    m = TAG.search(name)
    return m.group(0) if m else None


def sweep(folder: Path, prefix: str) -> list[Path]:
    """Remove the entries of ``folder`` whose name starts with ``prefix`` and carries the tag of an
    owner that is gone; returns what was removed. Nothing else is touched."""
    removed = []
    try:
        names = os.listdir(folder)
    except OSError:
        return removed
    for name in names:
        if not name.startswith(prefix):
            continue
        owner = owner_of(name[len(prefix):])
        if owner is None or alive(owner) or owner == tag():
            continue
        p = Path(folder) / name
        if remove(p):
            removed.append(p)
    return removed


def remove(p: Path) -> bool:
    """Remove whatever stands at ``p`` (a folder with its content; a link, not its target)."""
    try:
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p)
        else:
            p.unlink()
    except OSError:
        return False
    return True
