"""All the cells of a design, in the order a GDS needs them (children first), and the GDS library.

Cells: ``PRIMARY``, ``SECONDARY`` (the subpixels), ``DUALPIX`` (one primary above N
secondaries), ``COLUMN_P`` / ``COLUMN_S`` (each column's bias, load and samplers),
``DUALPIX_COL`` (the dual pixel with its column circuits: the primary's above, the
secondaries' below) and, on request, ``ARRAY_RxC`` (references of DUALPIX).
"""
from __future__ import annotations

from collections import OrderedDict

import gdstk

from .techview import LayoutTech


def build_cells(design) -> "OrderedDict[str, object]":
    """{name: Canvas} of every cell, children first; a RuleError / RouteError when one cannot
    be drawn."""
    from .columns import dual_pixel_column
    from .dual import dual_pixel
    lt = LayoutTech(design.tech)
    cells, dual = dual_pixel(design, lt)
    out = OrderedDict(cells)
    out["DUALPIX"] = dual
    col_cells, top = dual_pixel_column(design, lt, dual)
    out.update(col_cells)
    out["DUALPIX_COL"] = top
    return out


def build_chip_cells(design, rows: int, cols: int, afe: bool = False, shield: str = "full"):
    """Every cell of an R x C chip (with ``afe``: every column's AFE; ``shield``: see
    :mod:`.shield`), children first, and the name of the chip cell."""
    from .chip import build_chip
    from .shield import add_shield, strip_pixel_shield
    cells = build_cells(design)
    if shield == "none":
        strip_pixel_shield(cells)
    lt = LayoutTech(design.tech)
    chip_cells = build_chip(design, lt, cells, rows, cols, afe)
    *below, top = chip_cells
    chip = chip_cells[top]
    shields = add_shield(lt, cells, chip, shield, chip.ports["readouts"])
    out = OrderedDict(cells)
    for name in below:
        out[name] = chip_cells[name]
    out.update(shields)
    out[top] = chip
    return out, top


def to_library(design, cells, rows: int = 0, cols: int = 0) -> gdstk.Library:
    """The GDS library of ``cells``; with ``rows`` x ``cols`` also ``ARRAY_RxC`` of DUALPIX."""
    lib = gdstk.Library(name=design.name, unit=1e-6, precision=1e-9)
    made = {}
    for name, cv in cells.items():
        made[name] = cv.to_gdstk(design.tech, made)
        lib.add(made[name])
    if rows and cols:
        dual = cells["DUALPIX"]
        w, h = dual.ports["width"], dual.ports["height"]
        arr = gdstk.Cell(f"ARRAY_{rows}X{cols}")
        arr.add(gdstk.Reference(made["DUALPIX"], (0, 0), columns=cols, rows=rows, spacing=(w * 1e-3, h * 1e-3)))
        lib.add(arr)
    return lib


def build_library(design, rows: int = 0, cols: int = 0) -> gdstk.Library:
    from .rules import check
    check(design)
    return to_library(design, build_cells(design), rows, cols)
