"""Content-hash cache of simulation results.

The key hashes the deck text, the bytes of every model file it includes, the
ngspice version and the backend, so a repeated sweep point is free and a
changed model file or simulator invalidates it. Entries are ``.npz`` files
written atomically under ``$PIXELKIT_CACHE`` (default ``~/.cache/pixelkit``).

An entry cannot lie: it stores its own key and a SHA-256 checksum over its
names, metadata and every array's bytes. An entry that is damaged (truncated,
flipped, empty, unreadable) or that holds another key's result (swapped,
copied) is reported on stderr, removed and re-simulated.

A run that needed the retry policy's looser options is stored under the key of
the deck it actually ran (its own key); the strict deck's key holds only a
redirect to it, so the next run neither repeats the failing strict run nor
passes the loose result off as a strict one.
"""
from __future__ import annotations

import hashlib
import io
import json
import os
import sys
from pathlib import Path

import numpy as np

from ..errors import PixelkitError
from ..fileio import write_atomic
from ..tech.modellib import files_fingerprint
from .result import Result


def cache_dir() -> Path:
    return Path(os.environ.get("PIXELKIT_CACHE", Path.home() / ".cache" / "pixelkit")) / "sim"


def key(deck_text: str, include_files: tuple, version: str, backend: str) -> str:
    h = hashlib.sha256()
    for part in (deck_text, files_fingerprint(tuple(sorted(str(f) for f in include_files))) if include_files else "",
                 version, backend):
        h.update(part.encode())
        h.update(b"\0")
    return h.hexdigest()


def entry_path(k: str) -> Path:
    return cache_dir() / k[:2] / f"{k}.npz"


def _checksum(meta_text: str, arrays: list[np.ndarray]) -> str:
    h = hashlib.sha256(meta_text.encode())
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _say(path: Path, what: str) -> None:
    sys.stderr.write(f"pixelkit: warning: cache entry {path} {what}; re-simulating\n")


def load(k: str, _depth: int = 0) -> Result | None:
    """The cached result of key ``k``, or None (absent, or damaged/mismatched: said and removed)."""
    path = entry_path(k)
    if not path.exists():
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            if "__sum__" not in z.files and "__meta__" in z.files:
                _drop(path)  # written by a pixelkit before entries carried a checksum: not damage
                return None
            meta_text = str(z["__meta__"])
            stored_sum = str(z["__sum__"])
            meta = json.loads(meta_text)
            names = meta["__names__"]
            arrays = [z["__time__"], *(z[f"v{i}"] for i in range(len(names)))]
    except Exception as exc:  # noqa: BLE001 - any fault of the file is a damaged entry
        _say(path, f"is damaged ({type(exc).__name__})")
        _drop(path)
        return None
    if _checksum(meta_text, arrays) != stored_sum:
        _say(path, "fails its checksum")
        _drop(path)
        return None
    if meta.get("__key__") != k:
        _say(path, "holds another key's result")
        _drop(path)
        return None
    if "__redirect__" in meta:
        target = meta["__redirect__"]
        return load(target, _depth + 1) if _depth == 0 and isinstance(target, str) else None
    meta = {m: v for m, v in meta.items() if m not in ("__names__", "__key__")}
    meta["cached"] = True
    return Result(arrays[0], dict(zip(names, arrays[1:])), meta)


def _drop(path: Path) -> None:
    try:
        path.unlink()
    except OSError:
        pass


def _write(k: str, meta: dict, time, vectors: list) -> None:
    meta_text = json.dumps(dict(meta, __key__=k))
    arrays = [np.asarray(time), *(np.asarray(v) for v in vectors)]
    buf = io.BytesIO()
    np.savez(buf, __meta__=meta_text, __sum__=_checksum(meta_text, arrays), __time__=arrays[0],
             **{f"v{i}": a for i, a in enumerate(arrays[1:])})
    try:
        write_atomic(entry_path(k), buf.getvalue())
    except (OSError, PixelkitError) as exc:  # a cache that cannot be written costs time, not results
        sys.stderr.write(f"pixelkit: warning: {exc}; continuing without caching\n")


def save(k: str, result: Result) -> None:
    names = list(result.vectors)
    _write(k, dict(result.meta, __names__=names), result.time, [result.vectors[n] for n in names])


def save_redirect(k: str, target: str, reason: str) -> None:
    """Record that the strict deck of key ``k`` failed and its retried result is under ``target``."""
    _write(k, {"__names__": [], "__redirect__": target, "reason": reason}, np.zeros(0), [])
