"""``pixelkit layout``: GDS, extraction and pictures."""
from __future__ import annotations

from pathlib import Path

import click

from .common import design_arg, emit, json_opt, main


@main.command()
@design_arg
@click.option("--out-dir", type=click.Path(file_okay=False), default="layouts", show_default=True)
@click.option("--rows", type=click.IntRange(1, 1000), default=2, show_default=True)
@click.option("--cols", type=click.IntRange(1, 1000), default=2, show_default=True)
@click.option("--golden", is_flag=True, help="(re)write layouts/golden/<design>.gds, the geometry baseline")
@json_opt
def layout(design, out_dir, rows, cols, golden, as_json):
    """Write the GDS (dual pixel + array), extract PD area/perimeter/photoactive area, draw 2D and 3D views."""
    from ..design import load_design
    from ..layout.cells import build_library
    from ..layout.flow import layout_design, write_gds
    d = load_design(design)
    if golden:
        click.echo(f"wrote {write_gds(build_library(d, 2, 2), Path('layouts/golden') / f'{d.name}.gds')}")
        return
    r = layout_design(d, Path(out_dir), rows, cols)
    emit(r, as_json, lambda x: "\n".join([
        f"GDS: {x['gds']} (cells {', '.join(x['cells'])})", f"pictures: {x['png']}, {x['png_3d']}",
        *(f"  {w}: PD {x[w]['pd_area_m2'] * 1e12:.3f} um2, perimeter {x[w]['pd_perimeter_m'] * 1e6:.2f} um, "
          f"photoactive {x[w]['photoactive_area_m2'] * 1e12:.4f} um2" for w in ("primary", "secondary")),
        f"  C_A = {x['c_a']:.4f}"]))
