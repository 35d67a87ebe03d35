"""The light shield (the top metal) over the chip, and what it leaves open.

``--shield`` chooses how much of the chip the top metal covers:

- ``full``: everything but the mask openings - the pixels (their shield is drawn in each
  subpixel: the cell but its opening, or its PD when unmasked), the column circuits, the AFEs
  and the periphery (cells ``SHIELD_*``, one per readout cell, placed as the readout is);
- ``pixels``: the pixels only, the readout left open (the chip of [Thesis2019], whose AFE and
  output stage saw light);
- ``none``: no shield at all.

A readout's shield is its cell less every top-metal shape of the cell and of the cells beside
it, grown by the wide-metal spacing (the shield is wide metal: GF180MCU M5.2b), with slivers
narrower than the metal's width removed - so it meets the top metal's rules by construction
(and the foundry deck checks it). The shield is tied to ``vss`` through the periphery's vss
strap, so it is no floating plate over the readout.

:func:`exposed_junctions` measures, from the GDS read back, the junction area (COMP and
n-well) that no metal covers, per block.
"""
from __future__ import annotations

from pathlib import Path

from .canvas import Box, Canvas, box

MODES = ("full", "pixels", "none")
PIXEL_CELLS = ("PRIMARY", "SECONDARY")
JUNCTION = ("active", "nwell")
METALS = ("metal1", "metal2", "metal3", "metal4", "metal5")


def strip_pixel_shield(cells: dict) -> None:
    """Remove the shield the subpixels draw (``--shield none``)."""
    for name in PIXEL_CELLS:
        cv = cells[name]
        cv.shapes = [s for s in cv.shapes if s.net != "shield"]
        for k in list(cv._seen):
            cv._seen[k] = [s for s in cv._seen[k] if s.net != "shield"]


def _region(boxes):
    import klayout.db as kdb
    r = kdb.Region()
    for b in boxes:
        r.insert(kdb.Box(b.x0, b.y0, b.x1, b.y1))
    return r.merged()


def _rects(region) -> list[Box]:
    import klayout.db as kdb
    out = []
    for poly in region.each():
        for t in poly.decompose_trapezoids(kdb.Polygon.TD_htrapezoids):
            bb = t.bbox()
            out.append(Box(bb.left, bb.bottom, bb.right, bb.top))
    return out


def cover(lt, area: Box, metal: list[Box]) -> list[Box]:
    """Rectangles of top metal over ``area`` keeping the shield spacing to ``metal`` (top-metal
    shapes of other nets), without slivers under the metal's width or area."""
    space = lt.nm("shield.space") if lt.has("shield.space") else lt.space("shield")
    layer = lt.tech.layout.aliases.get("shield", "shield")
    w = lt.width(layer)
    region = _region([area]) - _region([b.grown(space) for b in metal])
    region = region.sized(-(w // 2)).sized(w // 2)         # an opening: nothing narrower than w stays
    a_min = lt.area(f"{layer}.area") if lt.has(f"{layer}.area") else 0
    region = region.with_area(int(a_min) + 1, None, False) if a_min else region
    return _rects(region.merged())


def _top_metal(cv: Canvas, dx: int = 0, dy: int = 0) -> list[Box]:
    layer = cv.rules.tech.layout.aliases.get("shield", "shield")
    return [s.box.moved(dx, dy) for s in cv.all_shapes() if s.layer in (layer, "shield") and not s.net.startswith("#")]


def shield_cell(lt, cell: Canvas, width: int, height: int) -> Canvas:
    """``SHIELD_<cell>``: the top metal over a readout cell that repeats every ``width`` nm."""
    metal = [b.moved(k * width, 0) for k in (-1, 0, 1) for b in _top_metal(cell)]
    out = Canvas(f"SHIELD_{cell.name}", lt)
    for b in cover(lt, box(0, 0, width, height), metal):
        out.add("shield", b, "shield")
    return out


def add_shield(lt, cells: dict, chip: Canvas, mode: str, readouts: dict) -> dict:
    """The shield cells of ``mode`` placed into ``chip``; returns the new cells.
    ``readouts``: {"s": (cell, y, count, step), "p": (...)} - the readout rows as placed."""
    out = {}
    if mode not in MODES:
        raise ValueError(mode)
    p = chip.ports
    margin, height = p["margin"], p["height"]
    layer = lt.tech.layout.aliases.get("shield", "shield")
    vss_x = p["straps"]["vss"]
    if mode == "full":
        metal = []
        for tag, (cell, y, count, step) in readouts.items():
            sc = shield_cell(lt, cell, step, cell.ports["height"])
            out[sc.name] = sc
            chip.place(sc, margin, y, {}, columns=count, spacing=step, register=False, name=f"xsh_{tag}")
            metal += _top_metal(cell, margin, y)
        edge = Canvas("SHIELD_EDGE", lt)
        for b in cover(lt, box(0, 0, margin, height), metal):
            edge.add("shield", b, "shield")
        out[edge.name] = edge
        chip.place(edge, 0, 0, {}, register=False, name="xsh_edge")
        ties = [y for y in _tie_rows(p)]
    elif mode == "pixels":
        y = p["hb"] + (p["rows"] * 0 + 1) * 2000           # a tab from the array's shield to the vss strap
        tab = box(vss_x - 1000, y, margin, y + 1000)
        chip.add("shield", tab, "shield")
        ties = [y + 500]
    else:
        return out
    lo, hi = p["reach"]["vss"]
    cut = lt.cut(f"via4")
    for y in ties:
        if lo <= y <= hi:
            chip.add("via4", box(vss_x - cut // 2, y - cut // 2, vss_x - cut // 2 + cut, y - cut // 2 + cut), "vss")
    del layer
    return out


def _tie_rows(p) -> list:
    """Where the shield meets the vss strap: the middle of each pixel row."""
    hd = p["pixel"][1]
    return [p["hb"] + r * hd + hd // 2 for r in range(p["rows"])]


def exposed_junctions(gds: Path, top: str, tech, blocks: dict) -> dict:
    """{block: {"junction_m2", "exposed_m2", "region"}} from the GDS read back: the junction
    (COMP or n-well) of each block, and the part of it no metal (metal1 - the top metal) covers.
    ``blocks``: {name: [Box, ...]} in nm, the top cell's coordinates."""
    import klayout.db as kdb
    from .gdsfile import read_klayout
    ly = read_klayout(gds, "gds")
    cell = ly.cell(top)
    dbu = ly.dbu

    def flat(name):
        lay = tech.layer(name)
        li = ly.find_layer(lay.layer, lay.datatype)
        return kdb.Region() if li is None else kdb.Region(cell.begin_shapes_rec(li))

    scale = round(1e-3 / dbu)      # nm -> database units
    junction = kdb.Region()
    for n in JUNCTION:
        junction += flat(n)
    junction.merge()
    metal = kdb.Region()
    for n in METALS:
        metal += flat(n)
    metal.merge()
    open_ = junction - metal
    out = {}
    unit = (dbu * 1e-6) ** 2
    for name, boxes in blocks.items():
        reg = kdb.Region()
        for b in boxes:
            reg.insert(kdb.Box(b.x0 * scale, b.y0 * scale, b.x1 * scale, b.y1 * scale))
        reg.merge()
        e = open_ & reg
        out[name] = {"junction_m2": (junction & reg).area() * unit, "exposed_m2": e.area() * unit, "region": e}
    return out


__all__ = ["MODES", "add_shield", "cover", "exposed_junctions", "shield_cell", "strip_pixel_shield"]
