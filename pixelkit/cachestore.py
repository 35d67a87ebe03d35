"""One checked store for the kit's caches: simulation results and report sections.

An entry is one file, ``$PIXELKIT_CACHE/<store>/<key[:2]>/<key>.entry`` (default cache
``~/.cache/pixelkit``), holding any number of named files::

    pixelkit-entry 1\\n
    <header length>\\n
    <header: JSON {"key": ..., "files": [[name, size, sha256], ...]}>
    <SHA-256 of the header>\\n
    <the files' bytes, one after the other>

Read, an entry is checked whole before anything in it is used: it must be a regular file
inside the cache (a pipe, a device, a folder or a symbolic link in its place is refused
without being opened for reading, :mod:`pixelkit.readfile`), no larger than the store's
bound, with the header's checksum, the key asked for (a swapped or copied entry holds
another key), every file's size and SHA-256, and nothing after the last file. An entry
that fails is said on stderr (``cache entry ...: <why>; <what happens instead>``),
removed, and rebuilt by the caller.

Written, an entry goes to ``<store>/tmp/<owner tag>.<random>`` first and is renamed into
place whole. The temporaries of a killed run (the tag names a process that is gone,
:mod:`pixelkit.owner`) are removed by the next process that opens the store.
"""
from __future__ import annotations

import hashlib
import json
import os
import sys
import tempfile
import threading
from pathlib import Path

from . import owner
from .readfile import FileRefused, read_bytes

MAGIC = b"pixelkit-entry 1\n"
_SWEPT: set = set()
_LOCK = threading.Lock()


def cache_root() -> Path:
    """``$PIXELKIT_CACHE``, default ``~/.cache/pixelkit``."""
    return Path(os.environ.get("PIXELKIT_CACHE", Path.home() / ".cache" / "pixelkit"))


class EntryDamaged(Exception):
    """Why an entry cannot be used (said to the user, then the entry is rebuilt)."""


def pack(key: str, files: dict[str, bytes]) -> bytes:
    header = json.dumps({"key": key, "files": [[n, len(b), hashlib.sha256(b).hexdigest()]
                                               for n, b in files.items()]}).encode()
    return b"".join([MAGIC, b"%d\n" % len(header), header, hashlib.sha256(header).hexdigest().encode(), b"\n",
                     *files.values()])


def unpack(blob: bytes, key: str) -> dict[str, bytes]:
    """The files of an entry, or EntryDamaged naming the first fault found."""
    if not blob.startswith(MAGIC):
        raise EntryDamaged("is not a pixelkit cache entry (damaged, or written by another version)")
    pos = len(MAGIC)
    nl = blob.find(b"\n", pos, pos + 20)
    try:
        n = int(blob[pos:nl]) if nl > 0 else -1
    except ValueError:
        n = -1
    if n < 0 or nl + 1 + n + 65 > len(blob):
        raise EntryDamaged("is truncated (its header is incomplete)")
    header = blob[nl + 1: nl + 1 + n]
    pos = nl + 1 + n
    if blob[pos:pos + 65] != hashlib.sha256(header).hexdigest().encode() + b"\n":
        raise EntryDamaged("fails its checksum (header)")
    pos += 65
    try:
        head = json.loads(header)
        stored_key, listing = head["key"], head["files"]
    except (ValueError, KeyError, TypeError):
        raise EntryDamaged("fails its checksum (header)") from None
    if stored_key != key:
        raise EntryDamaged("holds another key's entry (swapped or copied)")
    files = {}
    for name, size, digest in listing:
        part = blob[pos:pos + size]
        if len(part) != size:
            raise EntryDamaged(f"is truncated (file {name!r}: {len(part)} of {size} bytes)")
        if hashlib.sha256(part).hexdigest() != digest:
            raise EntryDamaged(f"fails its checksum (file {name!r})")
        files[name] = part
        pos += size
    if pos != len(blob):
        raise EntryDamaged(f"has {len(blob) - pos} bytes after its last file")
    return files


class Store:
    """The entries of one cache (``name``: ``sim`` or ``report``), read with the bound of ``kind``
    (:data:`pixelkit.readfile.LIMITS`); ``instead``: what the caller does when an entry is refused."""

    def __init__(self, name: str, kind: str, instead: str):
        self.name, self.kind, self.instead = name, kind, instead

    def root(self) -> Path:
        return cache_root() / self.name

    def path(self, key: str) -> Path:
        return self.root() / key[:2] / f"{key}.entry"

    def _say(self, path: Path, why: str) -> None:
        sys.stderr.write(f"pixelkit: warning: cache entry {path} {why}; {self.instead}\n")

    def load(self, key: str) -> dict[str, bytes] | None:
        """The files of entry ``key``, or None (absent; or refused: said and removed)."""
        path = self.path(key)
        self._sweep()
        if not os.path.lexists(path):
            return None
        if not self._inside(path):   # nothing read or removed through the link
            self._say(path, "lies outside the cache (a link among its folders)")
            return None
        try:
            blob = read_bytes(path, "cache entry", self.kind, follow=False)
            return unpack(blob, key)
        except FileRefused as exc:   # refused without being opened for reading
            self._say(path, f"is refused: {exc.value} (expected {exc.allowed})")
        except EntryDamaged as exc:
            self._say(path, str(exc))
        self.drop(key)
        return None

    def _inside(self, path: Path) -> bool:
        root = os.path.realpath(self.root())
        return os.path.commonpath([root, os.path.realpath(path.parent)]) == root

    def drop(self, key: str) -> None:
        """Remove entry ``key`` whatever stands in its place (a folder too: the cache is the kit's)."""
        owner.remove(self.path(key))

    def save(self, key: str, files: dict[str, bytes]) -> None:
        """Write entry ``key`` whole (temporary in ``tmp/``, then renamed); a cache that cannot be
        written costs time, not results: said once, and the run goes on."""
        path = self.path(key)
        tmpdir = self.root() / "tmp"
        self._sweep()
        tmp = None
        try:
            tmpdir.mkdir(parents=True, exist_ok=True)
            path.parent.mkdir(parents=True, exist_ok=True)
            if not self._inside(path):
                raise OSError(0, "a link among its folders leads out of the cache")
            fd, tmp = tempfile.mkstemp(prefix=f"{owner.tag()}.", dir=tmpdir)
            with os.fdopen(fd, "wb") as fh:
                fh.write(pack(key, files))
            if path.is_dir() and not path.is_symlink():
                owner.remove(path)   # a folder in the way: the cache is the kit's
            os.replace(tmp, path)
            tmp = None
        except OSError as exc:
            sys.stderr.write(f"pixelkit: warning: cannot write cache entry {path}: "
                             f"{exc.strerror or exc}; continuing without caching\n")
        finally:
            if tmp is not None:
                try:
                    os.unlink(tmp)
                except OSError:
                    pass

    def _sweep(self) -> None:
        """Once per process and store: remove the temporaries of runs that are gone."""
        root = self.root()
        with _LOCK:
            if root in _SWEPT:
                return
            _SWEPT.add(root)
        owner.sweep(root / "tmp", "")
