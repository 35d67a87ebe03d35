"""Parametric GDS layout of the integrated dual pixel and its arrays (gdstk).

Cells (lengths in um, origin at the lower-left corner of each cell):

- ``PRIMARY`` (pitch x pitch): the primary PD, its five transistors (active,
  poly gate, two contacts each) in the strip beside the PD, a metal1 column bus,
  the top-metal light shield with an opening over the whole PD (unmasked).
- ``SECONDARY`` (pitch x pitch): the 5 x 5 um PD, its transistors, and the shield
  with a square mask opening of the design's area centred on the PD.
- ``DUALPIX`` (primary pitch wide, primary + secondary pitch tall): one PRIMARY
  above a row of ``secondary_per_pixel`` SECONDARY references.
- ``ARRAY_RxC``: one repeated reference of DUALPIX (built by reference, not by
  copying polygons).

Every coordinate is snapped to the technology's grid. The layout rules are
checked first (``rules.check``), with errors naming the rule and the place.
"""
from __future__ import annotations

import math

import gdstk

from .rules import RuleError, check, check_layers

UM = 1e6  # metres -> um
EPS = 1e-6  # um: tolerance of fit checks against rounding


def _layer(tech, name):
    l_ = getattr(tech.layers, name)
    return {"layer": l_.layer, "datatype": l_.datatype}


def _snap(x: float, grid: float) -> float:
    return round(x / grid) * grid


def _rect(cell, x0, y0, x1, y1, tech, layer, grid):
    cell.add(gdstk.rectangle((_snap(x0, grid), _snap(y0, grid)), (_snap(x1, grid), _snap(y1, grid)),
                             **_layer(tech, layer)))


def opening_side(area_m2: float, grid_um: float) -> float:
    """Side (um) of the square mask opening, snapped to the grid."""
    return _snap(math.sqrt(area_m2) * UM, grid_um)


def _transistor(cell, x, y, w, l_, ext, tech, grid, horizontal):
    """Active (w x (l + 2 ext)), poly gate (l x (w + 0.4)) and two contacts at (x, y)."""
    c = 0.22
    if not horizontal:
        _rect(cell, x, y, x + w, y + l_ + 2 * ext, tech, "active", grid)
        _rect(cell, x - 0.2, y + ext, x + w + 0.2, y + ext + l_, tech, "poly", grid)
        for yc in (y + (ext - c) / 2, y + ext + l_ + (ext - c) / 2):
            _rect(cell, x + (w - c) / 2, yc, x + (w + c) / 2, yc + c, tech, "contact", grid)
    else:
        _rect(cell, x, y, x + l_ + 2 * ext, y + w, tech, "active", grid)
        _rect(cell, x + ext, y - 0.2, x + ext + l_, y + w + 0.2, tech, "poly", grid)
        for xc in (x + (ext - c) / 2, x + ext + l_ + (ext - c) / 2):
            _rect(cell, xc, y + (w - c) / 2, xc + c, y + (w + c) / 2, tech, "contact", grid)


def _place_devices(cell, design, pd_box, pitch, grid, name):
    """Fill the strip right of the PD, then the strip above it; RuleError if they do not fit."""
    tech, dev = design.tech, design.pixel.devices
    ext = tech.mos.diff_ext * UM
    edge = tech.rules.pd_to_cell_edge * UM
    gap = 0.3
    sizes = [(getattr(dev, f"{n}_w") * UM, getattr(dev, f"{n}_l") * UM) for n in ("ec", "tg", "rst", "sf", "rs")]
    x0, y = pd_box[2] + gap + 0.2, edge
    placed = 0
    for w, l_ in sizes:   # right strip, gates horizontal, stacked upwards
        h = l_ + 2 * ext
        if x0 + w + 0.2 > pitch - edge + EPS or y + h > pitch - edge + EPS:
            break
        _transistor(cell, x0, y, w, l_, ext, tech, grid, False)
        y += h + gap
        placed += 1
    x, y0 = edge, pd_box[3] + gap + 0.2
    for w, l_ in sizes[placed:]:  # top strip, gates vertical, left to right
        length = l_ + 2 * ext
        if y0 + w + 0.2 > pitch - edge + EPS or x + length > pd_box[2] + EPS:
            raise RuleError("transistors_fit", f"{name} cell", f"the five transistors do not fit beside "
                            f"the {pd_box[2] - pd_box[0]:.2f} x {pd_box[3] - pd_box[1]:.2f} um PD in a "
                            f"{pitch:g} um cell")
        _transistor(cell, x, y0, w, l_, ext, tech, grid, True)
        x += length + gap


def subpixel_cell(design, which: str) -> gdstk.Cell:
    tech, sub = design.tech, getattr(design, which)
    grid = tech.rules.grid * UM
    pitch = sub.pitch * UM
    edge = tech.rules.pd_to_cell_edge * UM
    cell = gdstk.Cell(which.upper())
    pd = (edge, edge, edge + sub.pd_width * UM, edge + sub.pd_height * UM)
    _rect(cell, 0, 0, pitch, pitch, tech, "boundary", grid)
    _rect(cell, *pd, tech, "pd", grid)
    _place_devices(cell, design, pd, pitch, grid, which.upper())
    _rect(cell, pitch - 0.6, 0, pitch - 0.1, pitch, tech, "metal1", grid)  # column bus
    if sub.mask_opening is None:
        opening = pd
    else:
        s = opening_side(sub.mask_opening, grid)
        cx, cy = (pd[0] + pd[2]) / 2, (pd[1] + pd[3]) / 2
        opening = (cx - s / 2, cy - s / 2, cx + s / 2, cy + s / 2)
    opening = tuple(_snap(v, grid) for v in opening)
    shield = gdstk.boolean(gdstk.rectangle((0, 0), (pitch, pitch)),
                           gdstk.rectangle(opening[:2], opening[2:]), "not", **_layer(tech, "shield"))
    cell.add(*shield)
    _rect(cell, *opening, tech, "opening", grid)
    return cell


def build_library(design, rows: int = 0, cols: int = 0) -> gdstk.Library:
    """Cells of the dual pixel; with ``rows``/``cols`` also the array ``ARRAY_RxC``."""
    check(design)
    lib = gdstk.Library(name=design.name, unit=1e-6, precision=1e-9)
    prim, sec = subpixel_cell(design, "primary"), subpixel_cell(design, "secondary")
    pp, sp = design.primary.pitch * UM, design.secondary.pitch * UM
    dual = gdstk.Cell("DUALPIX")
    dual.add(gdstk.Reference(prim, (0, sp)))
    dual.add(gdstk.Reference(sec, (0, 0), columns=design.secondary_per_pixel, rows=1, spacing=(sp, 0)))
    lib.add(prim, sec, dual)
    if rows and cols:
        arr = gdstk.Cell(f"ARRAY_{rows}X{cols}")
        arr.add(gdstk.Reference(dual, (0, 0), columns=cols, rows=rows, spacing=(pp, pp + sp)))
        lib.add(arr)
    return lib


def check_at_load(design) -> None:
    """Every rule the design file alone decides: :func:`check`, the layer map, and that the
    pixel's transistors fit beside each PD (a dry run of the cell generator, nothing written)."""
    check_layers(design.tech)
    check(design)
    for which in ("primary", "secondary"):
        try:
            subpixel_cell(design, which)
        except RuleError as exc:
            if not exc.field:
                exc.field, exc.value = f"{which}.pitch", getattr(design, which).pitch
            raise
