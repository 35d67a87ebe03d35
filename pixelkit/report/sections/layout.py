"""Layout section: the generated GDS (dual pixel + a 2 x 2 array), its 2D picture and off-screen 3D
view, and the geometry extracted back from the GDS.

Independent path: the areas and perimeters are extracted from the written GDS polygons
(``layout.extract``, klayout/gdstk), not taken from the design file; the table sets them beside
the design file's values and the thesis's [Thesis2019] C_A.
"""
from __future__ import annotations

from ...layout.flow import layout_design
from . import Checked, Figure, Section, Table

TITLE = "Layout"
THESIS_C_A = 15.1 * 13.55 / (5.0 * 5.0)   # thesis: 15.1 x 13.55 um primary PD, 5 x 5 um secondary


def build(ctx) -> Section:
    d = ctx.design
    folder = ctx.figure("layout/x").parent
    ctx.progress("layout: GDS, extraction, 2D and 3D pictures")
    r = layout_design(d, folder, 2, 2, pictures=True)
    rows, checked = [], []
    for w in ("primary", "secondary"):
        x, sub = r[w], getattr(d, w)
        rows += [[w, "PD area (um2)", x["pd_area_m2"] * 1e12, sub.area * 1e12],
                 [w, "PD perimeter (um)", float(x["pd_perimeter_m"]) * 1e6, sub.perimeter * 1e6],
                 [w, "photoactive area (um2)", x["photoactive_area_m2"] * 1e12, sub.photoactive_area * 1e12]]
        # GDS coordinates are on a 1 nm grid: 0.1 % covers the rounding of a few-um PD
        checked += [Checked(f"layout.{w}.pd_area_m2", x["pd_area_m2"], "m2", tol_rel=1e-3),
                    Checked(f"layout.{w}.photoactive_area_m2", x["photoactive_area_m2"], "m2", tol_rel=1e-3)]
    c_a_design = d.primary.area / d.secondary.area
    rows.append(["both", "C_A = A_pd,primary / A_pd,secondary", r["c_a"], c_a_design])
    thesis = f"; [Thesis2019] 15.1 x 13.55 um / 5 x 5 um = {THESIS_C_A:.4g}" if ctx.reference else ""
    checked.append(Checked("layout.c_a", r["c_a"], "1", tol_rel=1e-3, note=f"design file {c_a_design:.4g}{thesis}"))
    def rel(p: str) -> str:
        return "layout/" + p.rsplit("/", 1)[-1]
    text = [f"The generator writes the GDS ({', '.join(r['cells'])}) for a 2 x 2 array; the PD area, "
            "perimeter and photoactive (mask-open) area are extracted back from the GDS polygons and set "
            f"beside the design file's values. C_A from the GDS is {r['c_a']:.4g} (design file "
            f"{c_a_design:.4g}{thesis}). The GDS is beside this "
            f"report: {rel(r['gds'])}."]
    return Section(
        TITLE, text=text,
        tables=[Table("layout_extracted", "Geometry extracted from the GDS against the design file",
                      ["subpixel", "figure", "extracted from GDS", "design file"], rows)],
        figures=[Figure(rel(r["png"]), "The integrated dual pixel, top view (generated GDS)"),
                 Figure(rel(r["png_3d"]), "The integrated dual pixel, 3D view (pyvista, off-screen)")],
        checked=checked, files=[rel(r["gds"])],
        data={"primary": r["primary"], "secondary": r["secondary"], "c_a": r["c_a"], "cells": r["cells"]})
