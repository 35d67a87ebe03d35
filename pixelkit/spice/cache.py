"""Content-hash cache of simulation results.

The key hashes the deck text, the bytes of every model file it includes, the
ngspice version and the backend, so a repeated sweep point is free and a
changed model file or simulator invalidates it. Entries are ``.npz`` files
written atomically under ``$PIXELKIT_CACHE`` (default ``~/.cache/pixelkit``).
"""
from __future__ import annotations

import hashlib
import io
import json
import os
from pathlib import Path

import numpy as np

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


def load(k: str) -> Result | None:
    path = cache_dir() / k[:2] / f"{k}.npz"
    if not path.exists():
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            meta = json.loads(str(z["__meta__"]))
            vectors = {n: z[f"v{i}"] for i, n in enumerate(meta.pop("__names__"))}
            time = z["__time__"]
    except (OSError, ValueError, KeyError):
        return None  # a damaged entry is simply re-simulated
    meta["cached"] = True
    return Result(time, vectors, meta)


def save(k: str, result: Result) -> None:
    names = list(result.vectors)
    meta = dict(result.meta, __names__=names)
    buf = io.BytesIO()
    np.savez(buf, __time__=result.time, __meta__=json.dumps(meta),
             **{f"v{i}": result.vectors[n] for i, n in enumerate(names)})
    write_atomic(cache_dir() / k[:2] / f"{k}.npz", buf.getvalue())
