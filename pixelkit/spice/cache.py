"""Content-hash cache of simulation results.

The key hashes the deck text, the bytes of every model file it includes (and of
the files those include, by base name and content: not by where they lie, so two
checkouts of the kit, or a model library moved, share their entries), the
ngspice version and the backend, so a repeated sweep point is free and a
changed model file or simulator invalidates it. The deck text names the library
only through the kit's link (``models/<file>``, :mod:`pixelkit.tech.modellib`). An entry is the result as an
``.npz`` (names, metadata, arrays) kept in the kit's one checked store
(:mod:`pixelkit.cachestore`, folder ``$PIXELKIT_CACHE/sim``): an entry that is
damaged (truncated, flipped, empty), holds another key's result (swapped,
copied) or is not a regular file (a pipe, a device, a folder, a link) is said on
stderr, removed and re-simulated.

A run that needed the retry policy's looser options is stored under the key of
the deck it actually ran (its own key); the strict deck's key holds only a
redirect to it, so the next run neither repeats the failing strict run nor
passes the loose result off as a strict one.
"""
from __future__ import annotations

import hashlib
import io
import json
import sys
from pathlib import Path

import numpy as np

from ..cachestore import Store
from ..readfile import FileRefused
from ..tech.modellib import content_fingerprint
from .result import Result

STORE = Store("sim", "sim-cache", "re-simulating")
_NPZ = "result.npz"


def cache_dir() -> Path:
    return STORE.root()


def key(deck_text: str, include_files: tuple, version: str, backend: str) -> str:
    h = hashlib.sha256()
    for part in (deck_text, content_fingerprint(tuple(str(f) for f in include_files)) if include_files else "",
                 version, backend):
        h.update(part.encode())
        h.update(b"\0")
    return h.hexdigest()


def entry_path(k: str) -> Path:
    return STORE.path(k)


def load(k: str, _depth: int = 0) -> Result | None:
    """The cached result of key ``k``, or None (absent, or refused: said and removed)."""
    files = STORE.load(k)
    if files is None:
        return None
    try:
        z = _arrays(files[_NPZ], STORE.path(k))
        meta = json.loads(str(z["__meta__"]))
        names = meta["__names__"]
        arrays = [z["__time__"], *(z[f"v{i}"] for i in range(len(names)))]
    except Exception as exc:  # noqa: BLE001 - checksummed, yet not a result: written by another version
        why = exc.value if isinstance(exc, FileRefused) else type(exc).__name__
        sys.stderr.write(f"pixelkit: warning: cache entry {STORE.path(k)} holds no result "
                         f"({why}); re-simulating\n")
        STORE.drop(k)
        return None
    if "__redirect__" in meta:
        target = meta["__redirect__"]
        return load(target, _depth + 1) if _depth == 0 and isinstance(target, str) else None
    meta = {m: v for m, v in meta.items() if m != "__names__"}
    meta["cached"] = True
    return Result(arrays[0], dict(zip(names, arrays[1:])), meta)


def _arrays(blob: bytes, path) -> dict:
    """The arrays of an entry's ``.npz`` (stored, uncompressed, as ``np.savez`` writes it), each
    member's header checked against the member's size before it is read (readfile.npy_array):
    a forged entry cannot make the kit allocate what it declares."""
    import zipfile

    from ..readfile import npy_array
    out = {}
    with zipfile.ZipFile(io.BytesIO(blob)) as zf:
        for info in zf.infolist():
            if not info.filename.endswith(".npy") or info.compress_type != zipfile.ZIP_STORED:
                raise ValueError(f"member {info.filename!r} is not a stored .npy array")
            with zf.open(info) as fh:
                out[info.filename[:-4]] = npy_array(io.BytesIO(fh.read(info.file_size + 1)), info.file_size,
                                                    path, "cache entry", kinds="biufcU")
    return out


def _write(k: str, meta: dict, time, vectors: list) -> None:
    buf = io.BytesIO()
    np.savez(buf, __meta__=json.dumps(meta), __time__=np.asarray(time),
             **{f"v{i}": np.asarray(a) for i, a in enumerate(vectors)})
    STORE.save(k, {_NPZ: buf.getvalue()})


def save(k: str, result: Result) -> None:
    names = list(result.vectors)
    _write(k, dict(result.meta, __names__=names), result.time, [result.vectors[n] for n in names])


def save_redirect(k: str, target: str, reason: str) -> None:
    """Record that the strict deck of key ``k`` failed and its retried result is under ``target``."""
    _write(k, {"__names__": [], "__redirect__": target, "reason": reason}, np.zeros(0), [])
