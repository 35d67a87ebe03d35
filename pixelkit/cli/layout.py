"""``pixelkit layout``: GDS, extraction and pictures."""
from __future__ import annotations

from pathlib import Path

import click

from .common import design_arg, emit, json_opt, load, main, out_opt, output_path


@main.command()
@design_arg
@out_opt("output folder (default: reports/<design>/layout)", folder=True)
@click.option("--rows", type=click.IntRange(1, 1000), default=2, show_default=True)
@click.option("--cols", type=click.IntRange(1, 1000), default=2, show_default=True)
@click.option("--golden", is_flag=True, help="(re)write layouts/golden/<design>.gds, the geometry baseline")
@json_opt
def layout(design, out, rows, cols, golden, as_json):
    """Write the GDS (dual pixel + array), extract PD area/perimeter/photoactive area, draw 2D and 3D views."""
    from ..layout.cells import build_library
    from ..layout.flow import layout_design, write_gds
    d = load(design)
    if golden:
        path = write_gds(build_library(d, 2, 2), Path("layouts/golden") / f"{d.name}.gds")
        emit({"gds": str(path)}, as_json, lambda x: f"wrote {x['gds']}")
        return
    r = layout_design(d, output_path(out, d, "layout"), rows, cols)
    emit(r, as_json, lambda x: "\n".join([
        f"GDS: {x['gds']} (cells {', '.join(x['cells'])})", f"pictures: {x['png']}, {x['png_3d']}",
        *(f"  {w}: PD {x[w]['pd_area_m2'] * 1e12:.3f} um2, perimeter {x[w]['pd_perimeter_m'] * 1e6:.2f} um, "
          f"photoactive {x[w]['photoactive_area_m2'] * 1e12:.4f} um2" for w in ("primary", "secondary")),
        f"  C_A = {x['c_a']:.4f}"]))
