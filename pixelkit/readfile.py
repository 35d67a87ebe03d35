"""Reading input files with a bound: every file the kit reads goes through here.

A file is stated (``os.stat``, which never blocks) before it is opened: anything
but a regular file - a named pipe, a device such as ``/dev/zero``, a socket, a
folder - is refused without being opened for reading, and so is a file larger
than any real one of its kind could be (``LIMITS``). The open itself uses
``O_NONBLOCK`` and the opened file is stated again, so a pipe swapped in between
the two cannot block the kit either; at most ``limit + 1`` bytes are read, so a
file that grows while it is read (or a ``/proc`` file that states size 0)
cannot make the kit grow without limit.

A refusal is a :class:`FileRefused` (a :class:`~pixelkit.errors.ConfigError`,
exit 2): one line with the path, what was found and what is allowed.

The bounds are set far above any real file of each kind (the reasons are in
``docs/input-files.md``); a caller with a better bound (an image whose size the
EMVA descriptor states) passes ``limit=``.
"""
from __future__ import annotations

import errno
import os
import stat

from .errors import ConfigError

MiB = 1 << 20
#: kind -> largest file of that kind the kit reads (bytes).
LIMITS = {
    "design": 4 * MiB,            # a design or technology TOML file (the reference design: 3 kB)
    "technology": 4 * MiB,
    "csv": 16 * MiB,              # measured / conditions rows (~100 bytes a row: 160,000 rows)
    "descriptor": 4 * MiB,        # EMVA 1288 descriptor (the reference set's: 20 kB for 100 steps)
    "model": 64 * MiB,            # a SPICE model file (GF180's sm141064.ngspice: 1.3 MB)
    "image": 1 << 40,             # an EMVA 1288 image: bounded by its descriptor (gap/emva.image_limit)
    "scene": 256 * MiB,           # a scene map (.csv, .npy, image) for an array
    "gds": 256 * MiB,             # a layout whose geometry a design uses (or `pixelkit signoff` checks)
    "netlist": 64 * MiB,          # a designer's SPICE netlist of a layout cell (`pixelkit signoff`)
    "report": 64 * MiB,           # a file of an earlier report (--baseline)
    "json": 64 * MiB,             # a golden / regression JSON file
    "sim-cache": 2048 * MiB,      # a simulation-cache entry (a whole-chip frame: a few MB)
    "report-cache": 512 * MiB,    # a report-section cache entry (its figures)
    "raw": 2048 * MiB,            # an ngspice raw file (pixelkit waves; a whole-chip frame: tens of MB)
    "extraction-cache": 512 * MiB,   # a post-layout extraction cache entry (the parasitics)
}


class FileRefused(ConfigError):
    """An input file that is not a regular file, too large, or unreadable."""

    def __init__(self, path, what: str, found: str, allowed: str, missing: bool = False):
        self.path, self.missing = str(path), missing
        super().__init__(str(path), what, found, allowed)


_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a named pipe"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"), (stat.S_ISLNK, "a symbolic link"))


def _kind_of(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def _size_text(n: int) -> str:
    if n >= MiB and (n % MiB == 0 or n >= 10 * MiB):
        return f"{n / MiB:.0f} MiB"
    return f"{n} bytes"


def _limit(kind: str, limit: int | None) -> int:
    return LIMITS[kind] if limit is None else int(limit)


def check_file(path, what: str, kind: str, limit: int | None = None, *, follow: bool = True) -> os.stat_result:
    """The stat of ``path`` if it is a regular file of at most the kind's bound; else FileRefused.

    ``follow=False``: a symbolic link is itself refused (the caches, whose entries are never links).
    """
    lim = _limit(kind, limit)
    try:
        st = os.stat(path) if follow else os.lstat(path)
    except FileNotFoundError:
        raise FileRefused(path, what, str(path), "an existing file", missing=True) from None
    except (OSError, ValueError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        if isinstance(exc, OSError) and exc.errno == errno.ELOOP:
            reason = "a loop of symbolic links"
        raise FileRefused(path, what, reason, "a readable regular file") from None
    if not stat.S_ISREG(st.st_mode):
        raise FileRefused(path, what, _kind_of(st.st_mode), f"a regular {kind} file")
    if st.st_size > lim:
        raise FileRefused(path, what, _size_text(st.st_size),
                          f"a {kind} file of at most {_size_text(lim)} (larger than any real one)")
    return st


def open_file(path, what: str, kind: str, limit: int | None = None, *, follow: bool = True):
    """A binary file object for ``path`` (checked as :func:`check_file`, then opened without blocking)."""
    check_file(path, what, kind, limit, follow=follow)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
    if not follow:
        flags |= getattr(os, "O_NOFOLLOW", 0)
    try:
        fd = os.open(path, flags)
    except OSError as exc:
        raise FileRefused(path, what, exc.strerror or str(exc), "a readable regular file") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):  # swapped for a pipe or device since it was stated
            raise FileRefused(path, what, _kind_of(st.st_mode), f"a regular {kind} file")
        if st.st_size > _limit(kind, limit):
            raise FileRefused(path, what, _size_text(st.st_size), f"a {kind} file of at most "
                                                                  f"{_size_text(_limit(kind, limit))}")
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def read_bytes(path, what: str, kind: str, limit: int | None = None, *, follow: bool = True) -> bytes:
    """The bytes of ``path``: at most the kind's bound, never blocking (see the module docstring)."""
    lim = _limit(kind, limit)
    with open_file(path, what, kind, limit, follow=follow) as fh:
        try:
            data = fh.read(lim + 1)
        except OSError as exc:
            raise FileRefused(path, what, exc.strerror or str(exc), "a readable regular file") from None
    if len(data) > lim:  # it grew while being read
        raise FileRefused(path, what, f"more than {_size_text(lim)}",
                          f"a {kind} file of at most {_size_text(lim)} (larger than any real one)")
    return data


def read_text(path, what: str, kind: str, limit: int | None = None, encoding: str = "utf-8-sig") -> str:
    """:func:`read_bytes` decoded (UTF-8, a byte-order mark allowed); a decoding fault names the byte."""
    blob = read_bytes(path, what, kind, limit)
    try:
        return blob.decode(encoding)
    except UnicodeDecodeError as exc:
        raise FileRefused(path, what, f"byte {exc.start}: {blob[exc.start:exc.start + 4]!r}",
                          "a UTF-8 text file") from None


def is_regular(path) -> bool:
    """True when ``path`` is a regular file (stated, never opened)."""
    try:
        return stat.S_ISREG(os.stat(path).st_mode)
    except (OSError, ValueError):
        return False




def sha256_file(path, what: str, kind: str, limit: int | None = None) -> str:
    """SHA-256 hex digest of ``path``, read in 1 MiB pieces (memory bounded; checked as :func:`open_file`)."""
    import hashlib
    h, lim, n = hashlib.sha256(), _limit(kind, limit), 0
    with open_file(path, what, kind, limit) as fh:
        while piece := fh.read(MiB):
            n += len(piece)
            if n > lim:
                raise FileRefused(path, what, f"more than {_size_text(lim)}", f"a {kind} file of at most "
                                                                             f"{_size_text(lim)}")
            h.update(piece)
    return h.hexdigest()


def npy_array(fh, size: int, path, what: str, *, ndim: int | None = None, max_items: int | None = None,
              kinds: str = "biufc"):
    """The ``.npy`` array at the position of the open binary file ``fh``, whose ``size`` bytes from
    there hold it. Its header is checked before anything is allocated (issue 44: a header that
    declares 100000 x 100000 made numpy ask for 74.5 GiB): a number type (no objects), ``ndim``
    dimensions when given, at most ``max_items`` items, and no more bytes declared than there are.
    Refused: a :class:`FileRefused` naming the file, the declared shape and what is allowed."""
    import numpy as np
    from numpy.lib import format as npf
    start = fh.tell()
    try:
        version = npf.read_magic(fh)
        read_header = {(1, 0): npf.read_array_header_1_0, (2, 0): npf.read_array_header_2_0}.get(version)
        if read_header is None:
            raise ValueError(f"format version {version[0]}.{version[1]} (1.0 and 2.0 are read)")
        shape, _fortran, dtype = read_header(fh)
    except (ValueError, EOFError) as exc:
        raise FileRefused(path, what, f"a damaged .npy header ({exc})", "a .npy file numpy writes") from None
    if dtype.hasobject or dtype.kind not in kinds:
        raise FileRefused(path, what, f"dtype {dtype}", "an array of numbers (integer, float or complex)"
                          + (" or text" if "U" in kinds else ""))
    if ndim is not None and len(shape) != ndim:
        raise FileRefused(path, what, f"shape {shape}", f"a {ndim}-D array")
    items = 1
    for n in shape:
        items *= int(n)
    left = size - (fh.tell() - start)
    if (max_items is not None and items > max_items) or items * dtype.itemsize > left:
        bound = f", at most {max_items} items" if max_items is not None else ""
        raise FileRefused(path, what, f"a header that declares shape {shape} of {dtype} ({items * dtype.itemsize} "
                                      f"bytes; {left} follow it)", f"an array the file holds whole{bound}")
    fh.seek(start)
    return np.lib.format.read_array(fh, allow_pickle=False)
