"""Extraction of the kit's own layouts: each net's wiring capacitance to ground and to every other
net, the resistance of long wires, from the technology's process stack (``[stack]``).

- ``nets.py``: the drawn cell's nets with their geometry, matched to the kit's netlist (LVS);
- ``capacitance.py``: the 2.5D model (area, fringe, lateral) on that geometry;
- ``fastcap.py``: the independent check, FastCap2 (a 3D field solver) on the same geometry.
"""
from __future__ import annotations

import tempfile
from pathlib import Path


AFE_CELLS = ("AFE_P", "AFE_S")


def chip_geometry(design, tops=("DUALPIX", "DUALPIX_COL", *AFE_CELLS)) -> dict:
    """{cell: nets.NetGeometry} of the cells ``tops``, drawn as a 2 x 2 chip under the full shield, with
    its AFEs when ``tops`` names one (the AFEs exist only in a chip; the other cells are drawn alike
    without them, their grid router being the costly part of the drawing)."""
    from ...tech.stack import require_stack
    from ..flow import write_gds
    from ..library import build_chip_cells, to_library
    from .nets import net_geometry
    require_stack(design.tech)
    with tempfile.TemporaryDirectory(prefix="pixelkit-pex-") as tmp:
        cells, _top = build_chip_cells(design, 2, 2, any(t in AFE_CELLS for t in tops), "full")
        gds = write_gds(to_library(design, cells), Path(tmp) / f"{design.name}.gds")
        return {t: net_geometry(gds, t, design) for t in tops}


def cell_geometry(design, top: str, gds: Path | None = None):
    """The ``nets.NetGeometry`` of layout cell ``top`` of ``design`` (drawn now unless ``gds`` is given)."""
    from ...tech.stack import require_stack
    from .nets import net_geometry
    require_stack(design.tech)
    if gds is not None:
        return net_geometry(gds, top, design)
    from ..flow import write_gds
    from ..library import build_library
    with tempfile.TemporaryDirectory(prefix="pixelkit-pex-") as tmp:
        path = write_gds(build_library(design), Path(tmp) / f"{design.name}.gds")
        return net_geometry(path, top, design)


def gds_geometry(design, gds: Path, tops=("DUALPIX", "DUALPIX_COL", *AFE_CELLS), context: str | None = None) -> dict:
    """{cell: nets.NetGeometry} of the cells ``tops`` of a GDS the designer gives (the kit's cell names,
    matched to the kit's netlists of ``design``); a cell it lacks is named. ``context``: a cell that
    places them (the chip): each geometry's ``cover`` is then the metal the chip draws over the cell
    (its shield strips), in the cell's own coordinates."""
    import klayout.db as kdb
    from ...errors import PixelkitError
    from ...tech.stack import require_stack
    from .nets import net_geometry
    require_stack(design.tech)
    layout = kdb.Layout()
    layout.read(str(gds))
    missing = [t for t in tops if layout.cell(t) is None]
    if missing:
        raise PixelkitError(f"{gds}: no cell {', '.join(missing)} (the post-layout view and the light map of "
                            f"design {design.name} read the kit's cells: {', '.join(tops)})")
    out = {t: net_geometry(gds, t, design) for t in tops}
    if context is not None and layout.cell(context) is not None:
        for t, g in out.items():
            g.cover = _cover(layout, context, t, design.tech)
    return out


def _cover(layout, context: str, cell: str, tech, depth: int = 0):
    """Metal (every metal layer) of ``context`` flattened, over the first placement of ``cell`` in it,
    moved into ``cell``'s coordinates and clipped to its extent. A cell the chip does not place itself
    (``DUALPIX_COL``: the chip stacks its column circuits with the AFEs instead) gets the union of its
    children's covers; None where none of it is placed."""
    import klayout.db as kdb
    top = layout.cell(context)
    target = layout.cell(cell)
    it = top.begin_instances_rec()
    trans = None
    while not it.at_end():
        if it.inst_cell().cell_index() == target.cell_index():
            trans = it.trans() * it.inst_trans()
            break
        it.next()
    if trans is None:
        if depth > 8:
            return None
        out = None
        for inst in target.each_inst():
            sub = _cover(layout, context, inst.cell.name, tech, depth + 1)
            if sub is not None:
                moved = sub.transformed(inst.cplx_trans)
                out = moved if out is None else out + moved
        return out.merged() if out is not None else None
    metal = kdb.Region()
    for m in ("metal1", "metal2", "metal3", "metal4", "metal5"):
        lay = tech.layer(m)
        li = layout.find_layer(lay.layer, lay.datatype)
        if li is not None:
            metal += kdb.Region(top.begin_shapes_rec(li))
    return (metal.transformed(trans.inverted()) & kdb.Region(target.bbox())).merged()
