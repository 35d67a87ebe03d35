"""Reader of ngspice raw files (binary or ASCII, real or complex).

A file that is damaged, truncated or holds a plot with no points raises
:class:`RawError` naming the file and the fault; the engine treats that run as
failed, so the retry policy runs (an aborted transient leaves a 0-point file).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import PixelkitError


class RawError(PixelkitError):
    """A raw file that cannot be read back: names the file and what is wrong."""

    def __init__(self, path, what: str):
        self.path = str(path)
        super().__init__(f"{path}: unreadable ngspice raw file: {what}")


def read_raw(path: str | Path) -> list[dict]:
    """All plots of a raw file: ``[{"plotname", "names", "data": {name: array}}]``.

    Vector names are lower-cased as ngspice writes them (``time``, ``v(pd)``, ``i(vdd)``).
    """
    try:
        blob = Path(path).read_bytes()
    except OSError as exc:
        raise RawError(path, exc.strerror or str(exc)) from None
    return parse_raw(blob, path)


def parse_raw(blob: bytes, path) -> list[dict]:
    """The plots of a raw file's bytes ``blob`` (``path`` names it in an error)."""
    try:
        plots = _plots(blob)
    except (ValueError, IndexError) as exc:
        raise RawError(path, str(exc)) from None
    if not plots:
        raise RawError(path, "no plot in the file")
    return plots


def _plots(blob: bytes) -> list[dict]:
    plots, pos = [], 0
    while pos < len(blob):
        header, pos = _header(blob, pos)
        if header is None:
            break
        names, n_pts, cplx, binary = header["names"], header["points"], header["complex"], header["binary"]
        n_var = len(names)
        if n_pts < 1 or n_var < 1:
            raise ValueError(f"plot '{header['plotname']}' has {n_pts} points and {n_var} vectors")
        if binary:
            width = 16 if cplx else 8
            size = n_pts * n_var * width
            if pos + size > len(blob):
                raise ValueError(f"truncated: {len(blob) - pos} of {size} data bytes")
            arr = np.frombuffer(blob, dtype=np.float64, count=size // 8, offset=pos)
            pos += size
            if cplx:
                arr = arr.view(np.complex128)
            arr = arr.reshape(n_pts, n_var)
        else:
            arr, pos = _ascii_values(blob, pos, n_pts, n_var, cplx)
        plots.append({"plotname": header["plotname"], "names": names,
                      "data": {n: np.array(arr[:, i]) for i, n in enumerate(names)}})
    return plots


def _header(blob: bytes, pos: int):
    info = {"names": [], "points": 0, "complex": False, "binary": True, "plotname": ""}
    n_vars = 0
    while True:
        end = blob.find(b"\n", pos)
        if end < 0:
            return None, len(blob)
        line = blob[pos:end].decode("latin-1").strip()
        pos = end + 1
        key, _, val = line.partition(":")
        key = key.strip().lower()
        if key == "plotname":
            info["plotname"] = val.strip()
        elif key == "flags":
            info["complex"] = "complex" in val.lower()
        elif key == "no. variables":
            n_vars = int(val)
        elif key == "no. points":
            info["points"] = int(val)
        elif key == "variables":
            for _ in range(n_vars):
                end = blob.find(b"\n", pos)
                if end < 0:
                    raise ValueError("truncated variable list")
                cols = blob[pos:end].decode("latin-1").split()
                pos = end + 1
                info["names"].append(cols[1].lower())
        elif key == "binary":
            return info, pos
        elif key == "values":
            info["binary"] = False
            return info, pos


def _ascii_values(blob, pos, n_pts, n_var, cplx):
    tokens = blob[pos:].decode("latin-1").split()
    if len(tokens) < n_pts * (n_var + 1):
        raise ValueError(f"truncated: {len(tokens)} of {n_pts * (n_var + 1)} values")
    dtype = np.complex128 if cplx else np.float64
    arr = np.zeros((n_pts, n_var), dtype=dtype)
    k = 0
    for p in range(n_pts):
        k += 1  # the point index
        for v in range(n_var):
            tok = tokens[k]
            k += 1
            if cplx:
                re_, im = tok.split(",")
                arr[p, v] = complex(float(re_), float(im))
            else:
                arr[p, v] = float(tok)
    return arr, len(blob)
