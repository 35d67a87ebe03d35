"""The ``pixelkit layout`` flow: GDS under the output folder, the SPICE netlist of each drawn cell
beside it, extraction, pictures, and on request the sign-off (DRC with the technology's deck,
the kit's LVS)."""
from __future__ import annotations

import filecmp
from datetime import datetime
from pathlib import Path

from ..fileio import atomic_target, check_target, commit, out_folder, write_atomic
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


def write_netlists(design, cells, folder: Path, top: str = SIGNOFF_TOP) -> dict:
    """``<cell>.spice`` beside the GDS for every cell the kit has a netlist of, and the sign-off
    cell ``top`` also flat (``<top>.flat.spice``, for LVS decks that compare a flattened layout)."""
    from .signoff.schematic import circuit_of, circuits_of, flat_view, lvs_view, spice_text
    out = {}
    for name in cells:
        if circuit_of(name) is not None:
            view = lvs_view(design, circuits_of(design, name))
            out[name] = str(write_atomic(Path(folder) / f"{name}.spice", spice_text(view, f"{design.name} {name}")))
    for name in dict.fromkeys((SIGNOFF_TOP, top)):   # the pixel with its columns, and the chip
        if name in cells:
            view = flat_view(lvs_view(design, circuits_of(design, name)))
            out[f"{name}.flat"] = str(write_atomic(Path(folder) / f"{name}.flat.spice",
                                                   spice_text(view, f"{design.name} {name}, flattened")))
    return out


def layout_design(design, out_dir: Path = Path("layouts"), rows: int = 2, cols: int = 2,
                  pictures: bool = True, drc: bool = False, lvs: bool = False, afe: bool = False,
                  shield: str = "full", foundry_lvs: bool = False, density: bool = False,
                  antenna: bool = False, fill: bool = False, drc_cache: bool = False) -> dict:
    """Every cell of an R x C chip (its readout with ``afe``; ``shield`` full / pixels / none) in
    one GDS, the netlists beside it, extraction, the shield's exposure per block, pictures and,
    on request, the sign-off of the chip cell."""
    from .library import build_chip_cells
    from .rules import check
    from .shield import exposed_junctions
    check(design)
    out_dir = Path(out_dir)
    places = _signoff_places(design, out_dir, drc, lvs, density or antenna, foundry_lvs)   # before any work
    cells, top = build_chip_cells(design, rows, cols, afe, shield)   # every rule and route checked first
    _make_places(places, top)
    lib = to_library(design, cells)
    gds = write_gds(lib, out_dir / f"{design.name}.gds")
    filled = None
    if fill:                                   # dummy fill for the density rules (layout/fill.py)
        from .fill import fill as add_fill
        filled = add_fill(gds, top, design.tech)
    spice = write_netlists(design, cells, out_dir, top)
    ex = extract(gds, design.tech)
    chip = cells[top]
    exposure = exposed_junctions(gds, top, design.tech, chip.ports["blocks"])
    n_pix = rows * cols
    openings = n_pix * (_opening(design.primary) + design.secondary_per_pixel * _opening(design.secondary))
    result = {"gds": str(gds), **ex, "spice": spice, "top": top, "rows": rows, "cols": cols, "afe": afe,
              **({"fill": filled} if filled else {}),
              "c_a": ex["primary"]["pd_area_m2"] / ex["secondary"]["pd_area_m2"],
              "cells": [c.name for c in lib.cells],
              "size_um": [chip.ports["width"] / 1000, chip.ports["height"] / 1000],
              "blocks": _areas(chip.ports["blocks"]),
              "shield": {"mode": shield, "openings_m2": openings,
                         "exposed_m2": sum(v["exposed_m2"] for v in exposure.values()),
                         "blocks": {k: {"junction_m2": v["junction_m2"], "exposed_m2": v["exposed_m2"]}
                                    for k, v in exposure.items()}}}
    from .chip import chip_size
    full = chip_size(chip.ports, design.primary.rows, design.primary.cols)
    result["full_chip_um"] = [full[0] / 1000, full[1] / 1000]
    result["cell_sizes"] = {("ARRAY" if name.startswith("ARRAY_") else name): _size_um(cv) for name, cv in cells.items()
                            if name in ("DUALPIX", "COLUMN_P", "COLUMN_S", "AFE_P", "AFE_S", "ROWDRV") or name.startswith("ARRAY_")}
    result["block_regions_um"] = {k: [[b.x0 / 1000, b.y0 / 1000, b.x1 / 1000, b.y1 / 1000] for b in v]
                                  for k, v in chip.ports["blocks"].items()}
    if pictures:
        from .render import plot_2d, view_3d, plot_exposure
        dual = next(c for c in lib.cells if c.name == "DUALPIX")
        result["png"] = str(plot_2d(dual, design.tech, out_dir / f"{design.name}_dualpix.png",
                                    f"{design.name}: integrated dual pixel"))
        result["png_3d"] = str(view_3d(dual, design.tech, out_dir / f"{design.name}_dualpix_3d.png"))
        result["png_shield"] = str(plot_exposure(result, exposure, out_dir / f"{design.name}_shield.png",
                                                 f"{design.name} {top}: junction left open (--shield {shield})"))
    if drc:
        from .signoff.drc import run_drc
        result["drc"] = run_drc(gds, top, design.tech, out_dir / "drc", cache=drc_cache).as_dict()
    if lvs:
        from .signoff.lvs import run_lvs, run_lvs_deck
        if design.tech.signoff.lvs_deck:   # the technology's own deck (another PDK's)
            result["lvs"] = run_lvs_deck(gds, top, design, out_dir / "lvs", Path(spice[top])).as_dict()
        else:
            result["lvs"] = run_lvs(gds, top, design, out_dir / "lvs").as_dict()
    result.update(foundry_checks(gds, top, design.tech, out_dir, Path(spice[top]), foundry_lvs, density, antenna))
    return result


def foundry_checks(gds: Path, top: str, tech, out_dir: Path, spice: Path | None, lvs: bool, density: bool,
                   antenna: bool) -> dict:
    """The foundry's own LVS (against ``spice``), density and antenna decks on ``top``, as asked:
    {"foundry_lvs" / "density" / "antenna": the result's dict, ``{"run": False, ...}`` where the
    decks are not installed}."""
    from .signoff.foundry import run_chip_drc, run_lvs as run_foundry_lvs
    out = {}
    if lvs:
        out["foundry_lvs"] = run_foundry_lvs(gds, top, spice, tech, Path(out_dir) / "lvs").as_dict()
    for which, asked in (("density", density), ("antenna", antenna)):
        if asked:
            r = run_chip_drc(gds, top, tech, Path(out_dir) / "drc", which)
            out[which] = {"run": True, **r.as_dict()}
    return out


def verdict(result: dict) -> int:
    """The exit status of a sign-off result: 1 when a check that ran failed (DRC violations, an LVS
    mismatch, density / antenna violations), else 5 when a check asked could not run, else 0."""
    failed = any(k in result and result[k].get("run", True) and not result[k].get(ok, True)
                 for k, ok in (("drc", "clean"), ("lvs", "match"), ("foundry_lvs", "match"), ("density", "clean"),
                               ("antenna", "clean")))
    if failed:
        return 1
    return 5 if any(isinstance(v, dict) and v.get("run") is False for v in result.values()) else 0


def _signoff_places(design, out_dir: Path, drc: bool, lvs: bool, chip_drc: bool = False,
                    foundry_lvs: bool = False) -> dict:
    """Before anything is drawn or run: the decks the sign-off will run verified (pinned by sha256,
    exit 2 naming the key otherwise) and the output folders checked (a link, a file or a device
    where ``drc`` or ``lvs`` should be, a device or a dangling link as ``out``, is refused, naming
    it; nothing made yet). Returns
    {folder: the names of the files the sign-off writes there}, for :func:`_make_places`."""
    from .signoff.decks import drc_deck, lvs_deck
    if drc:
        drc_deck(design.tech)
    if lvs and design.tech.signoff.lvs_deck:
        lvs_deck(design.tech)
    places = {out_dir: ()}
    if drc or chip_drc:   # the foundry's density / antenna decks write there too (their own names)
        places[out_dir / "drc"] = ("{top}.lyrdb", "{top}.drc.log") if drc else ()
    if lvs or foundry_lvs:
        places[out_dir / "lvs"] = (("{top}.lvsdb", "{top}.ext.cir", "{top}.lvs.log") if design.tech.signoff.lvs_deck
                                   else ("{top}.lvsdb",)) if lvs else ()
    for folder, names in places.items():
        out_folder(folder, root=folder == out_dir, make=False)
    return places


def _make_places(places: dict, top: str) -> None:
    """The checked folders made, the files' places checked (the top cell is known now: a folder,
    device or pipe where the sign-off writes a file is refused before any deck runs)."""
    for i, (folder, names) in enumerate(places.items()):
        out_folder(folder, root=i == 0)
        for name in names:
            check_target(folder / name.format(top=top))


def _opening(sub) -> float:
    """The area the shield leaves open over one subpixel, as the design asks: its mask opening,
    or its whole PD when it is unmasked."""
    return sub.mask_opening if sub.mask_opening is not None else sub.pd_width * sub.pd_height


def _size_um(cv) -> list:
    """[width, height] in um of a cell's boundary."""
    b = next(s.box for s in cv.shapes if s.layer == "boundary")
    return [b.w / 1000, b.h / 1000]


def block_boxes(result: dict) -> dict:
    """The blocks' regions of a layout result as boxes in nm (what ``exposed_junctions`` takes)."""
    from .canvas import Box
    return {k: [Box(*(round(x * 1000) for x in b)) for b in v] for k, v in result["block_regions_um"].items()}


def _areas(blocks: dict) -> dict:
    """Area (m2) of each block's region."""
    return {k: sum(b.w * b.h for b in v) * 1e-18 for k, v in blocks.items()}
