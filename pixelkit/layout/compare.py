"""Geometry regression: XOR of two GDS files, cell by cell and layer by layer."""
from __future__ import annotations

from collections import defaultdict

import gdstk


def _flat(cell):
    by_layer = defaultdict(list)
    for p in cell.get_polygons():
        by_layer[(p.layer, p.datatype)].append(p)
    return by_layer


def xor_report(a: gdstk.Library, b: gdstk.Library) -> dict:
    """{"missing_cells", "extra_cells", "diff": {cell: {layer: area um2}}}; empty when identical."""
    ca, cb = {c.name: c for c in a.cells}, {c.name: c for c in b.cells}
    out = {"missing_cells": sorted(set(ca) - set(cb)), "extra_cells": sorted(set(cb) - set(ca)), "diff": {}}
    for name in sorted(set(ca) & set(cb)):
        fa, fb = _flat(ca[name]), _flat(cb[name])
        for layer in sorted(set(fa) | set(fb)):
            x = gdstk.boolean(fa.get(layer, []), fb.get(layer, []), "xor", precision=1e-4)
            area = sum(p.area() for p in x)
            if area > 1e-9:
                out["diff"].setdefault(name, {})[f"{layer[0]}/{layer[1]}"] = area
    return out


def identical(report: dict) -> bool:
    return not (report["missing_cells"] or report["extra_cells"] or report["diff"])
