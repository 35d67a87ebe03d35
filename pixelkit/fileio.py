"""Writing output files whole or not at all (temporary file, then rename).

A temporary is named ``.<name>.<owner tag>.<random>`` (:mod:`pixelkit.owner`): one left by a
killed run is removed by the next write of the same file once its owner is gone.

Files get the mode an ordinary ``open(path, "w")`` would give (0666 minus the
umask), not the 0600 of the temporary file they start as.
"""
from __future__ import annotations

import os
import tempfile
import threading
from pathlib import Path

from . import owner

_UMASK_LOCK = threading.Lock()


def _umask() -> int:
    with _UMASK_LOCK:  # reading the umask means setting it; put it straight back
        mask = os.umask(0o022)
        os.umask(mask)
    return mask


def _honour_umask(tmp) -> None:
    os.chmod(tmp, 0o666 & ~_umask())


def staging_dir(parent: Path, prefix: str) -> Path:
    """A new folder in ``parent`` to build an output in before renaming it into place, with the
    mode ``mkdir`` gives (0777 minus the umask), not the 0700 of ``tempfile.mkdtemp``."""
    d = Path(tempfile.mkdtemp(prefix=prefix, dir=parent))
    os.chmod(d, 0o777 & ~_umask())
    return d


def honour_umask_tree(root: Path) -> None:
    """Folders 0777 and files 0666 minus the umask under ``root`` (copies of cached or staged files
    keep the mode they were made with; the user's output gets the user's umask)."""
    mask = _umask()
    for dirpath, dirnames, filenames in os.walk(root):
        os.chmod(dirpath, 0o777 & ~mask)
        for name in filenames:
            path = os.path.join(dirpath, name)
            if not os.path.islink(path):
                os.chmod(path, 0o666 & ~mask)


def path_kind(path: str | os.PathLike) -> str | None:
    """"file", "dir", "other" or None (absent or unusable, e.g. a name too long).

    ``Path.is_file()`` raises on ENAMETOOLONG and similar; user-given paths go
    through here so such a name is an ordinary "not there", never a traceback.
    """
    import stat
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return None
    return "file" if stat.S_ISREG(mode) else "dir" if stat.S_ISDIR(mode) else "other"


def check_output(path: str | os.PathLike) -> Path:
    """``path`` if a file or folder can be written there; else one line naming it and why.

    Called before a long run, so an unwritable or misplaced ``--out`` is found first,
    not after the simulations.
    """
    from .errors import PixelkitError
    path = Path(path)
    probe = path
    while path_kind(probe) is None:
        if probe.parent == probe:
            break
        probe = probe.parent
    if probe != path and path_kind(probe) != "dir":
        raise PixelkitError(f"{path}: cannot write here: {probe} is a file, not a folder")
    if probe != path:
        try:
            name_max = os.pathconf(probe, "PC_NAME_MAX")
        except (OSError, ValueError):
            name_max = 255
        for part in path.relative_to(probe).parts:
            if len(os.fsencode(part)) > name_max:
                raise PixelkitError(f"{path}: cannot write here: the name {part[:40]!r}... is longer than the "
                                    f"{name_max} bytes this file system allows")
    if not os.access(probe, os.W_OK | (os.X_OK if path_kind(probe) == "dir" else 0)):
        raise PixelkitError(f"{path}: cannot write here: {probe} is not writable")
    return path


def write_atomic(path: str | os.PathLike, data: str | bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder."""
    from .errors import PixelkitError
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        if path.is_dir():
            raise IsADirectoryError(21, "a folder is in the way")
        owner.sweep(path.parent, f".{path.name}.")   # a killed run's temporary of this file
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.{owner.tag()}.", dir=path.parent)
    except OSError as exc:
        raise PixelkitError(f"{path}: cannot write: {exc.strerror or exc}") from None
    mode = "wb" if isinstance(data, bytes) else "w"
    try:
        with os.fdopen(fd, mode) as fh:
            fh.write(data)
        _honour_umask(tmp)
        os.replace(tmp, path)
    except BaseException as exc:
        if os.path.exists(tmp):
            os.unlink(tmp)
        if isinstance(exc, OSError):
            raise PixelkitError(f"{path}: cannot write: {exc.strerror or exc}") from None
        raise
    return path


def atomic_target(path: str | os.PathLike) -> tuple[Path, Path]:
    """A temporary path beside ``path`` for writers that want a file name.

    Call :func:`commit` with both when the writer has finished.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    owner.sweep(path.parent, f".{path.stem}.")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.{owner.tag()}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    return path, Path(tmp)


def commit(path: Path, tmp: Path) -> Path:
    _honour_umask(tmp)
    os.replace(tmp, path)
    return path


def moved_path(value: str, old_dir: Path, new_dir: Path) -> str:
    """A path relative to a file in ``old_dir``, rewritten to mean the same file from ``new_dir``
    (absolute paths unchanged): a design written to another folder keeps its technology and GDS."""
    p = Path(value)
    if p.is_absolute():
        return value
    return os.path.relpath((Path(old_dir) / p).resolve(), Path(new_dir).resolve())


def reports_root() -> Path:
    """Where outputs go when no ``--out`` is given: ``$PIXELKIT_REPORTS``, default ``./reports``."""
    return Path(os.environ.get("PIXELKIT_REPORTS", "reports"))


def json_default(x):
    """``json.dumps(..., default=json_default)``: numpy scalars and arrays as numbers and lists."""
    import numpy as np
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    return str(x)
