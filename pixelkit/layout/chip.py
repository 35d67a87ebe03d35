"""Arrays R x C with their readout: the dual pixels as one array reference, every column's
circuit (and with ``afe`` its AFE) as a row of references at each edge, the row lines and the
supplies brought to straps and pins at the left edge.

Floor plan of ``CHIP_RxC[_AFE]`` (origin lower left; ``M`` the left margin):

- ``ARRAY_RxC`` at (M, hb): the dual pixels abut, so each row's lines (metal3, EC / TG / RST /
  RS of both arrays, the supplies) run across the array and each column line (metal4) runs
  through all rows into the readout at its end, as ``DUALPIX_COL`` has it;
- under the array one ``READOUT_S`` per secondary column (``COLUMN_S`` above ``AFE_S``), over it
  one ``READOUT_P`` per primary column (``COLUMN_P`` under ``AFE_P``, the AFE mirrored so that
  its input faces the column circuit); without ``afe`` the column circuits alone;
- in the margin, vertical metal4 straps: the supplies (``vdd`` and ``vss`` over the whole
  height, joining the array's and the readouts' lines; ``vpdr``, ``vrst``), the global-shutter
  controls ``ec_*`` / ``tg_*`` (every row's line, as the simulated array ties them) and the AFEs'
  ``vref``; every other line (``rst_*`` / ``rs_*`` of each row, the readouts' clocks) runs to
  the left edge, where it is a pin;
- per-column pins at the bottom and top edges: ``out_*``, ``nbias_*`` and ``nb_*`` (the
  AFE's bias) of each column;
- with the boosted gate drive (``circuits.rowdriver``): a bank of ``ROWDRV`` cells above the margin,
  one per EC / TG / RST line, their inputs the pins ``<line>_in``, their rail the strap ``vgate``
  (:func:`_driver_bank`); the driven lines are then no pins.

The straps meet the lines with a via3 of the lines' own width (the foundry allows a via
overlap under 0.04 um on two sides when the other two overlap 0.06 um), so no line needs a
wider pad next to its neighbours.
"""
from __future__ import annotations

import math
from collections import OrderedDict

from ..circuits.rowdriver import boosted, driven_lines, driver_input
from .canvas import Box, Canvas, box
from .dual import CONTROLS, SUPPLIES
from .rowdriver import row_driver_layout
from .primitives import pad_side
from .rules import RuleError

KIND_SUFFIX = {"primary": "p", "secondary": "s"}
#: strap order from the array's edge outwards; the first two run the whole height
STRAPS = ("vdd", "vss", "vpdr", "vrst", "ec_p", "tg_p", "ec_s", "tg_s", "vref")
CLEAR = 1500        # nm between the array / readouts and the nearest strap (MIM plates: metal4 1.2 um off)
PIN_ROOM = 1000     # nm left of the last strap where the pins are


def mirrored(cv: Canvas, name: str) -> Canvas:
    """``cv`` (a flat cell) mirrored in y: its top edge becomes its bottom edge."""
    h = cv.ports["height"]
    out = Canvas(name, cv.rules)
    for s in cv.shapes:
        out.add(s.layer, Box(s.box.x0, h - s.box.y1, s.box.x1, h - s.box.y0), s.net)
    for lb in cv.labels:
        out.label(lb.layer, lb.x, h - lb.y, lb.text)
    for s in cv.all_shapes():
        if s.net.startswith("#"):
            out.block([s.layer], Box(s.box.x0, h - s.box.y1, s.box.x1, h - s.box.y0), s.net)
    assert not cv.placements, "only a flat cell is mirrored"
    p = dict(cv.ports)
    p["lines"] = {n: h - y for n, y in cv.ports.get("lines", {}).items()}
    p["top"], p["bottom"] = cv.ports.get("bottom", {}), cv.ports.get("top", {})
    out.ports = p
    return out


def readout_cells(design, lt, cells: dict) -> dict:
    """``AFE_S``, ``AFE_P`` and the readouts ``READOUT_S`` (``COLUMN_S`` over ``AFE_S``) and
    ``READOUT_P`` (``COLUMN_P`` under the mirrored ``AFE_P``)."""
    from .afe import afe_layout
    out = {}
    for kind, col_name, afe_name, ro_name in (("secondary", "COLUMN_S", "AFE_S", "READOUT_S"),
                                              ("primary", "COLUMN_P", "AFE_P", "READOUT_P")):
        col = cells[col_name]
        width = lt.snap(getattr(design, kind).pitch * 1e9)
        tr = col.ports["tracks"]
        afe = afe_layout(design, lt, kind, width, tr["out"], tr["nbias"], afe_name)
        hc, ha = col.ports["height"], afe.ports["height"]
        ro = Canvas(ro_name, lt)
        nets = {"out": "in", "nbias": "nbias"}
        if kind == "secondary":
            ro.place(afe, 0, 0, {n: n for n in ("in", "out", "nbias", "nb", *afe.ports["lines"])}, name="xafe")
            ro.place(col, 0, ha, nets, name="xcol")
            lines = {**{("afe", n): y for n, y in afe.ports["lines"].items()},
                     **{("col", n): ha + y for n, y in col.ports["lines"].items()}}
            pins = {n: x for n, x in afe.ports["bottom"].items()}
            edge = 0
        else:
            afe = mirrored(afe, afe_name)
            ro.place(col, 0, 0, nets, name="xcol")
            ro.place(afe, 0, hc, {n: n for n in ("in", "out", "nbias", "nb", *afe.ports["lines"])}, name="xafe")
            lines = {**{("col", n): y for n, y in col.ports["lines"].items()},
                     **{("afe", n): hc + y for n, y in afe.ports["lines"].items()}}
            pins = {n: x for n, x in afe.ports["top"].items()}
            edge = hc + ha
        ro.add("boundary", box(0, 0, width, hc + ha), "")
        ro.ports = {"width": width, "height": hc + ha, "lines": lines, "pins": pins, "pin_y": edge,
                    "afe_height": ha, "column_height": hc}
        out[afe_name] = afe
        out[ro_name] = ro
    return out


def column_readouts(cells: dict) -> dict:
    """Without AFEs the column circuits are the readout: their lines and their out / nbias pins."""
    out = {}
    for col_name, edge_top in (("COLUMN_S", False), ("COLUMN_P", True)):
        col = cells[col_name]
        tr = col.ports["tracks"]
        out[col_name] = {"lines": {("col", n): y for n, y in col.ports["lines"].items()},
                         "pins": {"out": tr["out"], "nbias": tr["nbias"]},
                         "pin_y": col.ports["height"] if edge_top else 0, "height": col.ports["height"]}
    return out


def check_size(design, rows: int, cols: int) -> None:
    """An array larger than the design's chip (or empty) is refused, naming the field."""
    for what, n, most in (("rows", rows, design.primary.rows), ("cols", cols, design.primary.cols)):
        if not 1 <= n <= most:
            raise RuleError("array_size", "array", f"{what} = {n}: the design's chip has {most} "
                            f"(primary.{what}); an array has 1 to {most}", f"primary.{what}", most)


def chip_name(rows: int, cols: int, afe: bool) -> str:
    return f"CHIP_{rows}X{cols}{'_AFE' if afe else ''}"


def build_chip(design, lt, cells: dict, rows: int, cols: int, afe: bool) -> dict:
    """The cells of an R x C chip: ``ARRAY_RxC``, the readouts and ``CHIP_RxC[_AFE]`` (children
    first). ``cells``: the cells of :func:`library.build_cells` (the dual pixel, the columns)."""
    check_size(design, rows, cols)
    n = design.secondary_per_pixel
    dual = cells["DUALPIX"]
    wp, hd = dual.ports["width"], dual.ports["height"]
    ps = lt.snap(design.secondary.pitch * 1e9)
    out = OrderedDict()
    arr = Canvas(f"ARRAY_{rows}X{cols}", lt)
    arr.place(dual, 0, 0, {}, columns=cols, spacing=wp, rows=rows, row_spacing=hd, register=False)
    arr.add("boundary", box(0, 0, cols * wp, rows * hd), "")
    arr.ports = {"width": cols * wp, "height": rows * hd}
    out[arr.name] = arr
    if afe:
        ro = readout_cells(design, lt, cells)
        out.update(ro)
        bottom, top = ro["READOUT_S"], ro["READOUT_P"]
        info = {k: v.ports for k, v in (("s", bottom), ("p", top))}
    else:
        bottom, top = cells["COLUMN_S"], cells["COLUMN_P"]
        info = {"s": column_readouts(cells)["COLUMN_S"], "p": column_readouts(cells)["COLUMN_P"]}
    hb, ht = info["s"]["height"], info["p"]["height"]
    drv = row_driver_layout(design, lt) if boosted(design) else None
    driven = driven_lines(rows) if drv else ()
    straps = (*STRAPS, "vgate") if drv else STRAPS
    n_straps = len(straps)
    pitch = lt.snap_up(lt.width("metal4") + lt.space("metal4") + 100)
    bank_w = len(driven) * drv.ports["width"] if drv else 0
    margin = lt.snap_up(bank_w + CLEAR + n_straps * pitch + PIN_ROOM)
    chip = Canvas(chip_name(rows, cols, afe), lt)
    chip.place(bottom, margin, 0, {}, columns=n * cols, spacing=ps, register=False, name="xro_s")
    chip.place(arr, margin, hb, {}, register=False, name="xarr")
    chip.place(top, margin, hb + rows * hd, {}, columns=cols, spacing=wp, register=False, name="xro_p")
    height = hb + rows * hd + ht
    width = margin + cols * wp
    # every horizontal line at the left edge: (net, y, line width)
    w3 = lt.width("metal3")
    lines = []
    for r in range(rows):
        y0 = hb + r * hd
        for tag, base, ly in (("s", y0, dual.ports["lines_s"]), ("p", y0 + ps, dual.ports["lines_p"])):
            for net, y in ly.items():
                name = net if net in SUPPLIES else (f"{net}_{tag}" if net in ("ec", "tg") else f"{net}_{tag}_{r}")
                lines.append((name, base + y, w3))
    for tag, y0 in (("s", 0), ("p", hb + rows * hd)):
        for (part, net), y in info[tag]["lines"].items():
            name = net if net in ("vdd", "vss", "vref") else f"{net}_{tag}"
            lines.append((name, y0 + y, _line_width(lt, bottom if tag == "s" else top, part)))
    strap_x = {net: margin - CLEAR - k * pitch for k, net in enumerate(straps)}
    reach: dict = {}
    cut = lt.cut("via3")
    ext = lt.nm("metal3.enclosure.via3")
    drive = {}      # driven line -> (x of its driver's output, y of the driver's bank)
    bank = None
    if drv:
        below = height
        height = _driver_bank(chip, lt, drv, driven, height, strap_x, reach, drive)
        bank = {"width": drv.ports["width"], "height": height - below}
        out[drv.name] = drv
        out.move_to_end(drv.name, last=False)
    for net, y, w in lines:
        if net in strap_x:
            x = strap_x[net]
            chip.add("metal3", box(x - cut // 2 - ext, y - w // 2, margin, y - w // 2 + w), net)
            chip.add("via3", box(x - cut // 2, y - cut // 2, x - cut // 2 + cut, y - cut // 2 + cut), net)
            lo, hi = reach.get(net, (y, y))
            reach[net] = (min(lo, y), max(hi, y))
        elif net in drive:   # a row's driven line: metal4 from its driver's output down to the line
            x, y_top = drive[net]
            w4, e4 = lt.width("metal4"), lt.nm("metal4.enclosure.via3")
            chip.add("metal3", box(x - cut // 2 - ext, y - w // 2, margin, y - w // 2 + w), net)
            chip.add("via3", box(x - cut // 2, y - cut // 2, x - cut // 2 + cut, y - cut // 2 + cut), net)
            chip.add("metal4", box(x - w4 // 2, y - cut // 2 - e4, x - w4 // 2 + w4, y_top), net)
        else:   # a pin at the left edge
            chip.add("metal3", box(0, y - w // 2, margin, y - w // 2 + w), net)
            chip.label("metal3_label", w, y, net)
    w4 = lt.width("metal4")
    # a strap that meets one line only (a 1 x 1 chip's ec / tg) is its via's pad: drawn at least the
    # metal's minimum area long (M4.3), centred on the via
    least = lt.snap_up(math.ceil(lt.area("metal4.area") / w4)) if lt.has("metal4.area") else 0
    for net, (lo, hi) in reach.items():
        x = strap_x[net]
        e = lt.nm("metal4.enclosure.via3")
        y0, y1 = lo - cut // 2 - e, hi + cut // 2 + e
        if y1 - y0 < least:
            mid = lt.snap((y0 + y1) / 2)
            y0, y1 = min(y0, mid - lt.snap_up(least / 2)), max(y1, mid + lt.snap_up(least / 2))
        chip.add("metal4", box(x - w4 // 2, y0, x - w4 // 2 + w4, y1), net)
        chip.label("metal4_label", x, (lo + hi) // 2, net)
    # per-column pins at the bottom and top edges
    for tag, y, count, step in (("s", info["s"]["pin_y"], n * cols, ps),
                                ("p", hb + rows * hd + info["p"]["pin_y"], cols, wp)):
        for j in range(count):
            for net, x in info[tag]["pins"].items():
                chip.label("metal4_label", margin + j * step + x, y + (1 if tag == "s" else -1), f"{net}_{tag}_{j}")
    chip.add("boundary", box(0, 0, width, height), "")
    blocks = _blocks(margin, hb, ht, rows, cols, wp, hd, ps, n, afe, info)
    if drv:   # the row drivers' bank and the room between it and the array: periphery
        blocks["periphery"].append(box(0, hb + rows * hd + ht, margin, height))
    chip.ports = {"readouts": {"s": (bottom, 0, n * cols, ps), "p": (top, hb + rows * hd, cols, wp)},"width": width, "height": height, "margin": margin, "hb": hb, "ht": ht, "rows": rows,
                  "cols": cols, "afe": afe, "straps": strap_x, "reach": reach, "pixel": (wp, hd),
                  "blocks": blocks, "drivers": driven, "bank": bank}
    out[chip.name] = chip
    return out


def _driver_bank(chip, lt, drv, driven, height: int, strap_x: dict, reach: dict, drive: dict) -> int:
    """The boosted rail's row drivers (``ROWDRV``, one per driven line) side by side above the
    chip's left margin, at x = 0, 1, 2 ... cell widths; returns the chip's new height. A global
    line's driver (EC / TG, tied by their straps) meets its strap through a metal3 jumper in the
    room between the array's readout and the bank; a row's line (RST) is reached by a metal4 strap
    of its own from the driver's output down to the line (``drive``: {line: (x, top)}, drawn with
    the line). The bank's shared lines (vss, vdd, vgate) run right to their straps (``reach``)."""
    cut, ext = lt.cut("via3"), lt.nm("metal3.enclosure.via3")
    w3, w4, e4 = lt.width("metal3"), lt.width("metal4"), lt.nm("metal4.enclosure.via3")
    row3 = lt.snap_up(pad_side(lt, "metal3") + lt.space("metal3") + 100)
    glob = [line for line in driven if line in strap_x]
    y_bank = lt.snap_up(height + 2 * CLEAR + len(glob) * row3)
    wd, stub, hdrv = drv.ports["width"], drv.ports["stub"], drv.ports["height"]

    def via(x, y, net):
        chip.add("via3", box(x - cut // 2, y - cut // 2, x - cut // 2 + cut, y - cut // 2 + cut), net)

    for k, line in enumerate(driven):
        x0 = k * wd
        chip.place(drv, x0, y_bank, {"in": driver_input(line), "out": line, "vss": "vss", "vdd": "vdd",
                                     "vgate": "vgate"}, register=False, name=f"xdrv_{line}")
        chip.label("metal4_label", x0 + drv.ports["in"], y_bank + hdrv - stub // 2, driver_input(line))
        xo = x0 + drv.ports["out"]
        if line in glob:
            y = height + CLEAR + glob.index(line) * row3
            chip.add("metal4", box(xo - w4 // 2, y - cut // 2 - e4, xo - w4 // 2 + w4, y_bank + stub // 2), line)
            via(xo, y, line)
            xs = strap_x[line]
            chip.add("metal3", box(xo - cut // 2 - ext, y - w3 // 2, xs + cut // 2 + ext, y - w3 // 2 + w3), line)
            via(xs, y, line)
            reach[line] = (y, y)
        else:
            drive[line] = (xo, y_bank + stub // 2)
    w = pad_side(lt, "metal3")
    for net, yl in drv.ports["lines"].items():
        y, xs = y_bank + yl, strap_x[net]
        chip.add("metal3", box(len(driven) * wd - w, y - w // 2, xs + cut // 2 + ext, y - w // 2 + w), net)
        via(xs, y, net)
        reach[net] = (y, y)
    return y_bank + hdrv


def chip_size(ports: dict, rows: int, cols: int) -> tuple[int, int]:
    """(width, height) in nm of the same chip with ``rows`` x ``cols`` dual pixels (with the boosted
    gate drive its bank of row drivers as wide as ``rows`` asks)."""
    wp, hd = ports["pixel"]
    margin, extra = ports["margin"], 0
    bank = ports.get("bank")
    if bank:
        margin += (len(driven_lines(rows)) - len(driven_lines(ports["rows"]))) * bank["width"]
        extra = bank["height"]
    return margin + cols * wp, ports["hb"] + rows * hd + ports["ht"] + extra


def _line_width(lt, cell, part: str) -> int:
    """Width of a readout line: the AFE draws its lines as wide as a via pad, the column cell at
    the metal's minimum width."""
    from .primitives import pad_side
    return pad_side(lt, "metal3") if part == "afe" else lt.width("metal3")


def _blocks(margin, hb, ht, rows, cols, wp, hd, ps, n, afe, info) -> dict:
    """Regions (nm, chip coordinates) of each block: the pixel array, the column circuits, the
    AFEs and the periphery (the left margin's straps and pins)."""
    top0 = hb + rows * hd
    x0, x1 = margin, margin + cols * wp
    out = {"pixel array": [box(x0, hb, x1, top0)]}
    if afe:
        ha_s, ha_p = info["s"]["afe_height"], info["p"]["afe_height"]
        out["column circuits"] = [box(x0, ha_s, x1, hb), box(x0, top0, x1, top0 + ht - ha_p)]
        out["AFE"] = [box(x0, 0, x1, ha_s), box(x0, top0 + ht - ha_p, x1, top0 + ht)]
    else:
        out["column circuits"] = [box(x0, 0, x1, hb), box(x0, top0, x1, top0 + ht)]
    out["periphery"] = [box(0, 0, margin, top0 + ht)]
    return out


__all__ = ["build_chip", "chip_name", "check_size", "readout_cells", "mirrored", "STRAPS"]
