"""``pixelkit size``: the mask opening and integration times with casadi."""
from __future__ import annotations

import click

from .common import design_arg, emit, json_opt, main


@main.command()
@design_arg
@click.option("--out", type=click.Path(dir_okay=False), default=None,
              help="sized design file (default: DESIGN_sized.toml beside DESIGN)")
@click.option("--sensitivity", "with_sens", is_flag=True,
              help="also re-size at +-10 % C_j, +-20 % SF bias, each corner, +-10 K")
@json_opt
def size(design, out, with_sens, as_json):
    """Size the secondary mask opening and the integration times (5 % / mid-scale criterion)."""
    from ..design import load_design
    from ..optimize.flow import size_design
    from ..report.text import size_text
    emit(size_design(load_design(design), out, with_sens), as_json, size_text)
