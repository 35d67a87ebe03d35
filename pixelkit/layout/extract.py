"""Extraction from GDS geometry: PD junction area and perimeter, photoactive area.

Reads the file back (it does not trust the generator): for the ``PRIMARY`` and
``SECONDARY`` cells, the photodiode is the n-well under the technology's photodiode
marker (``nwell and pd_marker``, merged), measured by area and outline perimeter; the
photoactive area is the part of it no metal covers (``PD not (metal1 or ... or metal5)``):
the light shield's opening, less any wire the layout runs over the junction.
"""
from __future__ import annotations

from pathlib import Path

import gdstk

from ..errors import ConfigError


METALS = ("metal1", "metal2", "metal3", "metal4", "metal5")


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
    from .gdsfile import read_gdstk
    lib = read_gdstk(path, "layout.gds")   # checked first: a pipe, a device, an empty / random / damaged file
    cells = {c.name: c for c in lib.cells}
    scale = lib.unit  # m per user unit
    out = {}
    for which in ("primary", "secondary"):
        cell = cells.get(which.upper())
        if cell is None:
            raise ConfigError(str(path), "layout.gds", str(path), f"a GDS with a {which.upper()} cell")
        polys = cell.get_polygons()
        pd = gdstk.boolean(_on(polys, tech.layer("nwell")), _on(polys, tech.layer("pd_marker")), "and")
        metal = [p for m in METALS for p in _on(polys, tech.layer(m))]
        if not pd:
            raise ConfigError(str(path), f"{which.upper()} cell", "no photodiode",
                              f"an n-well ({tech.layer('nwell')}) under the photodiode marker "
                              f"({tech.layer('pd_marker')})")
        open_ = gdstk.boolean(pd, metal, "not")
        out[which] = {"pd_area_m2": _area(pd) * scale ** 2, "pd_perimeter_m": _perimeter(pd) * scale,
                      "photoactive_area_m2": _area(open_) * scale ** 2}
    return out
