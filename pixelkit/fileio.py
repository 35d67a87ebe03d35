"""Writing output files whole or not at all (temporary file, then rename)."""
from __future__ import annotations

import os
import tempfile
from pathlib import Path


def write_atomic(path: str | os.PathLike, data: str | bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    mode = "wb" if isinstance(data, bytes) else "w"
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, mode) as fh:
            fh.write(data)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def atomic_target(path: str | os.PathLike) -> tuple[Path, Path]:
    """A temporary path beside ``path`` for writers that want a file name.

    Call :func:`commit` with both when the writer has finished.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    return path, Path(tmp)


def commit(path: Path, tmp: Path) -> Path:
    os.replace(tmp, path)
    return path


def reports_root() -> Path:
    """Where outputs go when no ``--out`` is given: ``$PIXELKIT_REPORTS``, default ``./reports``."""
    return Path(os.environ.get("PIXELKIT_REPORTS", "reports"))
