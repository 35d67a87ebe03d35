"""``pixelkit signoff GDS --netlist CELL.spice``: DRC, foundry and kit LVS, extraction, post-layout
netlist and light map of a layout the kit did not draw (docs/layout-signoff-any.md)."""
from __future__ import annotations

import sys
from pathlib import Path

import click

from .types import FilePath

from ..errors import ConfigError
from .common import emit, json_opt, main
from .layout import foundry_lines

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


def _drc(d: dict) -> list:
    return [f"DRC ({Path(d['deck']).name}, {d['klayout']}, {d['seconds']:g} s): "
            + ("clean" if d["clean"] else f"{d['total']} violation(s)")] + \
        [f"  {v['rule']} x{v['count']} in {v['cell']}: {v['description'].splitlines()[0]} (first at {v['where']})"
         for v in d["violations"]]


def _pex(p: dict) -> list:
    big = sorted(p["total_F"].items(), key=lambda kv: -kv[1])[:8]
    return [f"extraction ({p['seconds']:g} s): {p['nets']} nets, {p['couplings']} couplings -> {p['table']}; "
            f"post-layout netlist {p['post_layout_netlist']}",
            "  largest totals: " + ", ".join(f"{n} {c * 1e15:.3f} fF" for n, c in big)]


def _light(lm: dict) -> list:
    return [f"light map: {lm['open_m2'] * 1e12:.4g} um2 of junction no metal covers -> {lm['table']}"] + \
        [f"  {j['net']}: {j['kind']} {j['area_m2'] * 1e12:.4g} um2" for j in lm["junctions"][:8]]


def _text(r: dict) -> str:
    lines = [f"{r['gds']}: cell {r['top']} against {r['netlist']} ({r['technology']}, {r['seconds']:g} s)"]
    for key, what, render in (("drc", "DRC", _drc), ("lvs", "LVS", None), ("pex", "extraction", _pex),
                              ("lightmap", "light map", _light)):
        x = r.get(key)
        if x is None:
            continue
        if not x.get("run", True):
            lines.append(f"{what}: NOT RUN - {x['reason']}")
        elif render is not None:
            lines += render(x)
        else:
            lines.append(f"LVS (kit extraction, {x['seconds']:g} s): " + (f"match ({x['nets']} nets in {r['top']})"
                         if x["match"] else f"{len(x['mismatches'])} mismatch(es)"))
            lines += [f"  {m}" for m in x["mismatches"]]
            lines += foundry_lines(r)
    dz = r.get("design")
    if dz:
        if "post_layout" in dz:
            pl = dz["post_layout"]
            lines.append(f"post-layout view of the design -> {pl['file']} (every SPICE command uses it with "
                         "--post-layout when the design names this GDS in [layout] gds): FD "
                         + ", ".join(f"{k} {v * 1e15:.3f} fF" for k, v in pl["fd_F"].items()))
        if "lightmap" in dz:
            lines += [f"light map through the readout: {c} AFE output error {x['error_V'] * 1e3:+.3f} mV "
                      f"({x['error_over_noise']:.1f} x the read noise)" for c, x in dz["lightmap"]["columns"].items()]
    lines.append({0: "signed off: every check asked ran and passed", 1: "NOT signed off: a check failed",
                  5: "NOT signed off: a check asked did not run"}[r["exit_status"]])
    return "\n".join(lines)


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
