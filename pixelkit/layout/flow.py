"""The ``pixelkit layout`` flow: GDS under layouts/, extraction, 2D and 3D pictures."""
from __future__ import annotations

import filecmp
from datetime import datetime
from pathlib import Path

from ..fileio import atomic_target, commit
from .cells import build_library
from .extract import extract


#: GDS headers carry a modification time; a fixed one makes equal geometry give equal bytes.
GDS_TIMESTAMP = datetime(2000, 1, 1)


def write_gds(lib, path: Path) -> Path:
    """Write ``lib`` deterministically; an unchanged file is left untouched (same bytes, same mtime)."""
    path, tmp = atomic_target(path)
    lib.write_gds(str(tmp), timestamp=GDS_TIMESTAMP)
    if path.is_file() and filecmp.cmp(path, tmp, shallow=False):
        tmp.unlink()
        return path
    return commit(path, tmp)


def layout_design(design, out_dir: Path = Path("layouts"), rows: int = 2, cols: int = 2,
                  pictures: bool = True) -> dict:
    from .render import plot_2d, view_3d
    lib = build_library(design, rows, cols)
    gds = write_gds(lib, Path(out_dir) / f"{design.name}.gds")
    ex = extract(gds, design.tech)
    result = {"gds": str(gds), **ex,
              "c_a": ex["primary"]["pd_area_m2"] / ex["secondary"]["pd_area_m2"],
              "cells": [c.name for c in lib.cells]}
    if pictures:
        dual = next(c for c in lib.cells if c.name == "DUALPIX")
        result["png"] = str(plot_2d(dual, design.tech, Path(out_dir) / f"{design.name}_dualpix.png",
                                    f"{design.name}: integrated dual pixel"))
        result["png_3d"] = str(view_3d(dual, design.tech, Path(out_dir) / f"{design.name}_dualpix_3d.png"))
    return result
