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
