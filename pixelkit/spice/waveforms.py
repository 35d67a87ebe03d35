"""Waveforms out of a :class:`Result`: CSV with units in the column names, or an ngspice raw file.

CSV columns: ``time_s``, then one per vector named ``v(node)_V`` or
``i(source)_A`` (hierarchy with '.', as ngspice names them), one row per time
point of the simulator. A raw file (``.raw``) is ngspice's binary format
(real, float64), readable by ngspice's ``load``, gwave, PySpice or
:func:`pixelkit.spice.raw.read_raw`.
"""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ..errors import ConfigError
from ..fileio import write_atomic
from .result import vector_key


def column_name(key: str) -> str:
    return f"{key}_{'A' if key.startswith('i(') else 'V'}"


def _select(result, vectors):
    if vectors is None:
        return result.names()
    keys = [vector_key(v) for v in vectors]
    missing = [k for k in keys if k not in result.vectors]
    if missing:
        raise ConfigError("", "waveform vector", missing[0], f"one of {', '.join(result.names()[:20])}...")
    return keys


def write_waveforms(result, path: Path, vectors=None) -> Path:
    """Write ``vectors`` (default: all) of ``result``; the format follows the suffix (.csv or .raw)."""
    path = Path(path)
    keys = _select(result, vectors)
    data = np.column_stack([result.time] + [np.real(result.vectors[k]) for k in keys])
    suffix = path.suffix.lower()
    if suffix == ".raw":
        return write_atomic(path, _raw_bytes(result, keys, data))
    if suffix not in (".csv", ".txt", ""):
        raise ConfigError("", "--waveforms", str(path), "a file name ending in .csv or .raw")
    buf = io.StringIO()
    np.savetxt(buf, data, delimiter=",", fmt="%.12g",
               header=",".join(["time_s", *(column_name(k) for k in keys)]), comments="")
    return write_atomic(path, buf.getvalue())


def _raw_bytes(result, keys, data) -> bytes:
    kinds = ["time"] + ["current" if k.startswith("i(") else "voltage" for k in keys]
    head = [f"Title: {result.meta.get('title', 'pixelkit')}", "Date: -",
            "Plotname: Transient Analysis", "Flags: real", f"No. Variables: {len(kinds)}",
            f"No. Points: {len(data)}", "Variables:"]
    head += [f"\t{i}\t{n}\t{kind}" for i, (n, kind) in enumerate(zip(["time", *keys], kinds))]
    head.append("Binary:")
    return ("\n".join(head) + "\n").encode() + np.ascontiguousarray(data, dtype="<f8").tobytes()
