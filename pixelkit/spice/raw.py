"""Reader of ngspice raw files (binary or ASCII, real or complex)."""
from __future__ import annotations

from pathlib import Path

import numpy as np


def read_raw(path: str | Path) -> list[dict]:
    """All plots of a raw file: ``[{"plotname", "names", "data": {name: array}}]``.

    Vector names are lower-cased as ngspice writes them (``time``, ``v(pd)``, ``i(vdd)``).
    """
    blob = Path(path).read_bytes()
    plots, pos = [], 0
    while pos < len(blob):
        header, pos = _header(blob, pos)
        if header is None:
            break
        names, n_pts, cplx, binary = header["names"], header["points"], header["complex"], header["binary"]
        n_var = len(names)
        if binary:
            width = 16 if cplx else 8
            size = n_pts * n_var * width
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
