"""Writing output files whole or not at all (temporary file, then rename), never through a link.

A temporary is named ``.<name>.<owner tag>.<random>`` (:mod:`pixelkit.owner`): one left by a
killed run is removed by the next write of the same file once its owner is gone.

Files get the mode an ordinary ``open(path, "w")`` would give (0666 minus the
umask), not the 0600 of the temporary file they start as.

Links and odd files (issue 44). The folder a user names for the output (``--out``, or the
folder of a file output) is theirs: it may be a link they made, it is followed. Below it,
everything is the kit's: every folder it writes into is created by the kit or must be a real
folder, every file it writes goes to a new temporary in that folder and is renamed over the
name (a rename never writes through a link: a link someone placed at a file's name is
replaced, its target left as it was), and a symbolic link, a device, a pipe or a file in the
place of a folder the kit needs, or a device, pipe or folder in the place of a file it writes,
is refused (:class:`~pixelkit.errors.PixelkitError`, exit 2, naming the path). The
user's folders are registered by :func:`out_folder` / :func:`check_output`; a writer checks
every folder between the file and the nearest registered one with ``lstat``, so a link placed
at ``<out>/drc`` is met before anything is written through it. The checks are made before the
work (``check_output``, ``out_folder``, ``check_target``) and again at each write.
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
    mode ``mkdir`` gives (0777 minus the umask), not the 0700 of ``tempfile.mkdtemp``. ``parent``
    is checked (or made) as :func:`out_folder` does; name ``prefix`` with the owner tag
    (``owner.tag()``) so a killed run's folder is swept by the next one."""
    from .errors import PixelkitError
    out_folder(parent)
    try:
        d = Path(tempfile.mkdtemp(prefix=prefix, dir=parent))
    except OSError as exc:
        raise PixelkitError(f"{parent}: cannot write: {exc.strerror or exc}") from None
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


#: the output folders the user named (absolute, as written: links in them are the user's)
_ROOTS: set[str] = set()
_ROOTS_LOCK = threading.Lock()


def _kind_no_follow(path) -> str | None:
    """"file", "dir", "link", "other" (device, pipe, socket) or None (absent / unusable name)."""
    import stat
    try:
        mode = os.lstat(path).st_mode
    except (OSError, ValueError):
        return None
    if stat.S_ISLNK(mode):
        return "link"
    return "file" if stat.S_ISREG(mode) else "dir" if stat.S_ISDIR(mode) else "other"


_WHAT = {"file": "a file", "link": "a symbolic link", "other": "a device, pipe or socket", "dir": "a folder"}


def _error(path, text: str):
    from .errors import PixelkitError
    return PixelkitError(f"{path}: {text}")


def _root_of(folder: str) -> str | None:
    """The nearest registered output folder at or above ``folder`` (absolute), or None."""
    with _ROOTS_LOCK:
        roots = list(_ROOTS)
    best = None
    for r in roots:
        if (folder == r or folder.startswith(r.rstrip(os.sep) + os.sep)) and (best is None or len(r) > len(best)):
            best = r
    return best


def _user_folder(path: str) -> None:
    """The folder the user named: followed if a link; made (with its parents) when absent."""
    kind = path_kind(path)
    if kind == "dir":
        return
    if kind is not None:
        raise _error(path, f"is {_WHAT[kind]} where the output needs a folder")
    if _kind_no_follow(path) == "link":
        raise _error(path, "is a symbolic link to nothing usable (dangling or a loop) where the output needs a "
                           "folder")
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as exc:
        raise _error(path, f"cannot make the output folder: {exc.strerror or exc}") from None


def _kit_folder(path: str, make: bool = True) -> bool:
    """A folder below the user's: a real folder, or made now (``make``); never a link. Returns
    whether it is there."""
    kind = _kind_no_follow(path)
    if kind == "dir":
        return True
    if kind is not None:
        raise _error(path, f"is {_WHAT[kind]} where the kit writes a folder of its own; remove it or choose "
                           "another --out")
    if not make:
        return False
    try:
        os.mkdir(path)
    except FileExistsError:   # made meanwhile: judge what is there now
        if _kind_no_follow(path) != "dir":
            raise _error(path, "was replaced while the kit made it; choose another --out") from None
    except OSError as exc:
        raise _error(path, f"cannot make this folder: {exc.strerror or exc}") from None
    return True


def out_folder(path: str | os.PathLike, root: bool = False, make: bool = True) -> Path:
    """``path`` as a folder the kit may write in, made if absent (before any long work).

    ``root=True``: the folder the user named (``--out``; registered, so what lies below it is
    checked as the kit's). Otherwise every folder from the nearest registered one down to
    ``path`` must be a real folder (a link, file or device there is refused, naming it) or is
    made; with none registered, ``path`` itself is taken as the user's. The folder must be
    writable. ``make=False``: only checked (what is there), nothing made. Returns ``path``.
    """
    path = Path(path)
    if "\0" in str(path):
        raise _error(ascii(str(path))[1:-1], "a path with a NUL character")
    full = os.path.abspath(path)
    top = full if root else _root_of(full)
    if top is None:
        top = full
    if not make and path_kind(top) is None and _kind_no_follow(top) is None:
        return path
    _user_folder(top)
    if root:
        with _ROOTS_LOCK:
            _ROOTS.add(full)
    rest = Path(full).relative_to(top).parts
    here = top
    for part in rest:
        here = os.path.join(here, part)
        if not _kit_folder(here, make):
            return path
    if not os.access(full, os.W_OK | os.X_OK):
        raise _error(path, "is not writable")
    return path


def check_target(path: str | os.PathLike) -> Path:
    """``path`` is free, a regular file or a symbolic link: what the kit writes there replaces it
    by a rename, which never follows a link (the link is replaced, its target left as it was). A
    device, a pipe, a socket or a folder in its place is refused, naming it."""
    kind = _kind_no_follow(path)
    if kind not in (None, "file", "link"):
        raise _error(path, f"is {_WHAT[kind]} where the kit writes a file; remove it or choose another --out")
    return Path(path)


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


def check_output(path: str | os.PathLike, folder: bool | None = None) -> Path:
    """``path`` if a file or folder can be written there; else one line naming it and why.

    Called before a long run, so an unwritable or misplaced ``--out`` is found first,
    not after the simulations. ``folder=True``: an output folder (a device, a file or a link
    to nothing there is refused); ``folder=False``: an output file (a device, a pipe or a
    folder in its place is refused; a link there is replaced, never followed); None: either. The output's folder is registered as the
    user's (:func:`out_folder`).
    """
    from .errors import PixelkitError
    path = Path(path)
    if "\0" in str(path):   # no file system takes it (os calls raise ValueError)
        raise PixelkitError(f"{ascii(str(path))[1:-1]}: cannot write here: a path with a NUL character")
    kind, own = path_kind(path), _kind_no_follow(path)
    if folder is True and kind not in (None, "dir"):
        raise PixelkitError(f"{path}: cannot write here: it is {_WHAT[kind]}, not a folder")
    if folder is True and kind is None and own == "link":
        raise PixelkitError(f"{path}: cannot write here: a symbolic link to nothing usable (dangling or a loop)")
    if folder is False:
        check_target(path)
        kind = own
    elif folder is None and kind == "other":
        raise PixelkitError(f"{path}: cannot write here: it is {_WHAT[kind]}")
    probe = path
    while path_kind(probe) is None:
        if probe.parent == probe:
            break
        probe = probe.parent
    if probe != path and path_kind(probe) != "dir":
        raise PixelkitError(f"{path}: cannot write here: {probe} is {_WHAT.get(path_kind(probe), 'not a folder')}, "
                            "not a folder")
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
    with _ROOTS_LOCK:   # the user's folder: links in it are theirs, what the kit makes below is checked
        _ROOTS.add(os.path.abspath(path if folder or kind == "dir" else path.parent))
    return path


def _prepare(path: Path, prefix: str, suffix: str = "") -> tuple[int, str]:
    """The folder of ``path`` checked or made (:func:`out_folder`), its place checked
    (:func:`check_target`), a killed run's temporary swept; a new temporary opened beside it."""
    from .errors import PixelkitError
    out_folder(path.parent)
    check_target(path)
    owner.sweep(path.parent, prefix)   # a killed run's temporary of this file
    try:
        return tempfile.mkstemp(prefix=f"{prefix}{owner.tag()}.", suffix=suffix, dir=path.parent)
    except OSError as exc:
        raise PixelkitError(f"{path}: cannot write: {exc.strerror or exc}") from None


def write_atomic(path: str | os.PathLike, data: str | bytes) -> Path:
    """Write ``data`` to ``path`` through a new temporary file in the same folder, renamed over it."""
    from .errors import PixelkitError
    path = Path(path)
    fd, tmp = _prepare(path, f".{path.name}.")
    mode = "wb" if isinstance(data, bytes) else "w"
    try:
        with os.fdopen(fd, mode) as fh:
            fh.write(data)
        _honour_umask(tmp)
        check_target(path)
        os.replace(tmp, path)
    except BaseException as exc:
        if os.path.lexists(tmp):
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
    fd, tmp = _prepare(path, f".{path.stem}.", path.suffix)
    os.close(fd)
    return path, Path(tmp)


def commit(path: Path, tmp: Path) -> Path:
    """Rename the finished temporary ``tmp`` over ``path`` (its place checked again first)."""
    _honour_umask(tmp)
    try:
        check_target(path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    os.replace(tmp, path)
    return path


def moved_path(value: str, old_dir: Path, new_dir: Path) -> str:
    """A path relative to a file in ``old_dir``, rewritten to mean the same file from ``new_dir``
    (absolute paths unchanged): a design written to another folder keeps its technology and GDS."""
    p = Path(value)
    if p.is_absolute():
        return value
    return os.path.relpath((Path(old_dir) / p).resolve(), Path(new_dir).resolve())


def move_into(src: str | os.PathLike, path: str | os.PathLike) -> Path:
    """Move a finished file that a tool wrote in the kit's own staging folder (on the same file
    system, e.g. :func:`staging_dir`) to ``path``: its folder and place checked, then one rename."""
    path = Path(path)
    out_folder(path.parent)
    return commit(path, Path(src))


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
