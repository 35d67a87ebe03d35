"""The ``pixelkit layout`` flow: GDS under the output folder, the SPICE netlist of each drawn cell
beside it, extraction, pictures, and on request the sign-off (DRC with the technology's deck,
the kit's LVS)."""
from __future__ import annotations

import filecmp
from datetime import datetime
from pathlib import Path

from ..fileio import atomic_target, commit, write_atomic
from .extract import extract
from .library import build_cells, to_library

#: GDS headers carry a modification time; a fixed one makes equal geometry give equal bytes.
GDS_TIMESTAMP = datetime(2000, 1, 1)
#: The cell the sign-off runs on: the dual pixel with its column circuits (every cell below it).
SIGNOFF_TOP = "DUALPIX_COL"


def write_gds(lib, path: Path) -> Path:
    """Write ``lib`` deterministically; an unchanged file is left untouched (same bytes, same mtime)."""
    path, tmp = atomic_target(path)
    lib.write_gds(str(tmp), timestamp=GDS_TIMESTAMP)
    if path.is_file() and filecmp.cmp(path, tmp, shallow=False):
        tmp.unlink()
        return path
    return commit(path, tmp)


def write_netlists(design, cells, folder: Path) -> dict:
    """``<cell>.spice`` beside the GDS for every cell the kit has a netlist of."""
    from .signoff.schematic import CELL_CIRCUIT, circuits_of, flat_view, lvs_view, spice_text
    out = {}
    for name in cells:
        if name in CELL_CIRCUIT:
            view = lvs_view(design, circuits_of(design, name))
            out[name] = str(write_atomic(Path(folder) / f"{name}.spice", spice_text(view, f"{design.name} {name}")))
    # the sign-off cell also flat, for LVS decks that compare a flattened layout
    view = flat_view(lvs_view(design, circuits_of(design, SIGNOFF_TOP)))
    out[f"{SIGNOFF_TOP}.flat"] = str(write_atomic(Path(folder) / f"{SIGNOFF_TOP}.flat.spice",
                                                  spice_text(view, f"{design.name} {SIGNOFF_TOP}, flattened")))
    return out


def layout_design(design, out_dir: Path = Path("layouts"), rows: int = 2, cols: int = 2,
                  pictures: bool = True, drc: bool = False, lvs: bool = False) -> dict:
    from .rules import check
    check(design)
    cells = build_cells(design)          # every rule and route checked before any file is written
    lib = to_library(design, cells, rows, cols)
    gds = write_gds(lib, Path(out_dir) / f"{design.name}.gds")
    spice = write_netlists(design, cells, Path(out_dir))
    ex = extract(gds, design.tech)
    result = {"gds": str(gds), **ex, "spice": spice,
              "c_a": ex["primary"]["pd_area_m2"] / ex["secondary"]["pd_area_m2"],
              "cells": [c.name for c in lib.cells]}
    if pictures:
        from .render import plot_2d, view_3d
        dual = next(c for c in lib.cells if c.name == "DUALPIX")
        result["png"] = str(plot_2d(dual, design.tech, Path(out_dir) / f"{design.name}_dualpix.png",
                                    f"{design.name}: integrated dual pixel"))
        result["png_3d"] = str(view_3d(dual, design.tech, Path(out_dir) / f"{design.name}_dualpix_3d.png"))
    if drc:
        from .signoff.drc import run_drc
        result["drc"] = run_drc(gds, SIGNOFF_TOP, design.tech, Path(out_dir) / "drc").as_dict()
    if lvs:
        from .signoff.lvs import run_lvs, run_lvs_deck
        if design.tech.signoff.lvs_deck:   # the technology's own deck (another PDK's)
            result["lvs"] = run_lvs_deck(gds, SIGNOFF_TOP, design, Path(out_dir) / "lvs",
                                         Path(spice[SIGNOFF_TOP])).as_dict()
        else:
            result["lvs"] = run_lvs(gds, SIGNOFF_TOP, design, Path(out_dir) / "lvs").as_dict()
    return result
