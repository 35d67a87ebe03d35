"""``pixelkit size``: the mask opening and integration times with casadi."""
from __future__ import annotations

import click

from .common import design_arg, emit, finishing, json_opt, load, main, out_opt, output_path, spice_opts, post_layout_opt


@main.command()
@design_arg
@out_opt("sized design file (default: reports/<design>/<design>_sized.toml)")
@click.option("--sensitivity", "with_sens", is_flag=True,
              help="also re-size at +-10 % C_j, +-20 % SF bias, each corner, +-10 K")
@spice_opts
@post_layout_opt
@json_opt
def size(design, out, with_sens, backend, jobs, as_json):
    """Size the secondary mask opening and the integration times (5 % / mid-scale criterion)."""
    from ..fileio import write_atomic
    from ..optimize.flow import size_result
    from ..report.text import size_text
    from ..spice.counter import spice_progress
    d = load(design)
    with spice_progress("size"):
        result, text = size_result(d, output_path(out, d, f"{d.name}_sized.toml"), with_sens, backend=backend)
    finishing()  # all computed: a Ctrl-C from here no longer stops the file or the summary
    write_atomic(result["sized_design"], text)
    emit(result, as_json, size_text)
