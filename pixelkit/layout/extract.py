"""Extraction from GDS geometry: PD junction area and perimeter, photoactive area.

Reads the file back (it does not trust the generator): for the ``PRIMARY`` and
``SECONDARY`` cells, the PD layer's polygons are merged and measured (area,
perimeter of the outline), and the photoactive area is the part of the PD not
covered by the light shield (``PD and not SHIELD``).
"""
from __future__ import annotations

from pathlib import Path

import gdstk

from ..errors import ConfigError
from ..fileio import path_kind


def _on(polys, layer):
    return [p for p in polys if (p.layer, p.datatype) == (layer.layer, layer.datatype)]


def _area(polys) -> float:
    return sum(p.area() for p in polys)


def _perimeter(polys) -> float:
    total = 0.0
    for p in polys:
        pts = p.points
        total += sum(((pts[i] - pts[i - 1]) ** 2).sum() ** 0.5 for i in range(len(pts)))
    return total


def extract(gds: str | Path, tech) -> dict:
    """{"primary": {pd_area_m2, pd_perimeter_m, photoactive_area_m2}, "secondary": {...}} from a GDS."""
    path = Path(gds)
    if path_kind(path) != "file":
        raise ConfigError(str(path), "layout.gds", str(path), "an existing GDS file")
    from ..readfile import check_file
    check_file(path, "layout.gds", "gds")   # a pipe or a device would block or fill gdstk's memory
    lib = gdstk.read_gds(str(path))
    cells = {c.name: c for c in lib.cells}
    scale = lib.unit  # m per user unit
    out = {}
    for which in ("primary", "secondary"):
        cell = cells.get(which.upper())
        if cell is None:
            raise ConfigError(str(path), "layout.gds", str(path), f"a GDS with a {which.upper()} cell")
        polys = cell.get_polygons()
        pd = gdstk.boolean(_on(polys, tech.layers.pd), [], "or")
        shield = _on(polys, tech.layers.shield)
        if not pd:
            raise ConfigError(str(path), f"{which.upper()} cell", "no PD shapes",
                              f"PD polygons on layer {tech.layers.pd.layer}/{tech.layers.pd.datatype}")
        open_ = gdstk.boolean(pd, shield, "not")
        out[which] = {"pd_area_m2": _area(pd) * scale ** 2, "pd_perimeter_m": _perimeter(pd) * scale,
                      "photoactive_area_m2": _area(open_) * scale ** 2}
    return out
