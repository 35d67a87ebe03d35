"""``pixelkit signoff GDS --netlist CELL.spice``: DRC, foundry and kit LVS, extraction, post-layout
netlist and light map of a layout the kit did not draw (docs/layout-signoff-any.md)."""
from __future__ import annotations

import sys
from pathlib import Path

import click

from .types import FilePath

from ..errors import ConfigError
from .common import emit, json_opt, main
from .signofftext import signoff_text as _text

ALL = ("drc", "lvs", "foundry-lvs", "pex", "lightmap", "density", "antenna")


def _skip(ctx, param, value) -> tuple:
    out = []
    for part in value or ():
        for x in part.split(","):
            x = x.strip()
            if x not in ALL:
                raise ConfigError("command line", "--skip", x, f"one or more of {', '.join(ALL)}")
            out.append(x)
    return tuple(out)


@main.command("signoff")
@click.argument("gds", type=FilePath(dir_okay=False))
@click.option("--netlist", required=True, type=FilePath(dir_okay=False),
              help="the SPICE netlist of the layout's top cell (a .subckt per cell LVS compares)")
@click.option("--top", default=None, help="the cell to sign off (default: the layout's one top cell)")
@click.option("--tech", "tech_name", default=None, help="a built-in technology name or a technology file "
              "(default: the --with-design's, else gf180mcu_3v3)")
@click.option("--with-design", "design_path", default=None, type=FilePath(dir_okay=False),
              help="a design whose cells the GDS holds (the kit's cell names): also its post-layout view and its "
                   "light map through the readout (SPICE) from this layout")
@click.option("--chip", is_flag=True, help="the top cell is a whole die: also the foundry's density and antenna decks")
@click.option("--skip", multiple=True, callback=_skip, help=f"checks not to run, comma-separated ({', '.join(ALL)})")
@click.option("--out", type=FilePath(file_okay=False), default=None,
              help="output folder (default: reports/signoff/<gds name>)")
@json_opt
def signoff_cmd(gds, netlist, top, tech_name, design_path, chip, skip, out, as_json):
    """Sign off a layout the kit did not draw: foundry DRC, foundry LVS (fd_pv) and the kit's LVS against
    the netlist, extraction (capacitance table, post-layout netlist), the junctions no metal covers.
    Exit 0 all asked ran and passed, 1 a check failed, 2 bad input (before any deck runs), 5 a check
    asked could not run (a deck not installed)."""
    from ..fileio import check_output, reports_root
    from ..layout.anylayout import signoff
    from ..tech.technology import load_technology
    design = None
    if design_path:
        from .common import load
        design = load(design_path, drawable=False)
        tech = design.tech
        if tech_name:
            raise ConfigError("command line", "--tech", tech_name, "no --tech with --with-design (its technology is used)")
    else:
        tech = load_technology(tech_name or "gf180mcu_3v3", relative_to=Path.cwd(), source="--tech")
    folder = check_output(Path(out) if out else reports_root() / "signoff" / Path(gds).stem, folder=True)
    r = signoff(gds, netlist, tech, folder, top, skip, chip, design)
    emit(r, as_json, _text)
    if r["exit_status"]:
        sys.exit(r["exit_status"])
