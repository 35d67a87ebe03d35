"""``pixelkit layout``: GDS, netlists of the drawn cells, extraction, pictures; ``--drc`` / ``--lvs``."""
from __future__ import annotations

import sys
from pathlib import Path

import click

from ..errors import ConfigError
from .common import design_arg, emit, json_opt, load, main, out_opt, output_path
from .signofftext import foundry_lines, signoff_text


def _render(x: dict) -> str:
    lines = [f"GDS: {x['gds']} (cells {', '.join(x['cells'])})",
             f"netlists: {', '.join(Path(p).name for p in x['spice'].values())}"]
    if "png" in x:
        lines.append(f"pictures: {x['png']}, {x['png_3d']}, {x['png_shield']}")
    lines += [f"  {w}: PD {x[w]['pd_area_m2'] * 1e12:.3f} um2, perimeter {x[w]['pd_perimeter_m'] * 1e6:.2f} um, "
              f"photoactive {x[w]['photoactive_area_m2'] * 1e12:.4f} um2" for w in ("primary", "secondary")]
    lines.append(f"  C_A = {x['c_a']:.4f}")
    sh = x["shield"]
    lines.append(f"{x['top']}: {x['size_um'][0]:.1f} x {x['size_um'][1]:.1f} um; shield {sh['mode']}: junction left "
                 f"open {sh['exposed_m2'] * 1e12:.4g} um2 (openings drawn {sh['openings_m2'] * 1e12:.4g} um2)")
    lines += [f"  {k}: {v * 1e12:.5g} um2, open {sh['blocks'][k]['exposed_m2'] * 1e12:.4g} um2"
              for k, v in x["blocks"].items()]
    if "drc" in x:
        d = x["drc"]
        head = f"DRC ({Path(d['deck']).name}, {d['top']}, {d['klayout']}, {d['seconds']:g} s): "
        lines.append(head + ("clean" if d["clean"] else f"{d['total']} violation(s)"))
        lines += [f"  {v['rule']} x{v['count']} in {v['cell']}: {v['description']} (first at {v['where']})"
                  for v in d["violations"]]
    if "lvs" in x:
        v = x["lvs"]
        lines.append(f"LVS ({v['top']}, kit extraction, {v['seconds']:g} s): "
                     + ("match" if v["match"] else f"{len(v['mismatches'])} mismatch(es)"))
        lines += [f"  {m}" for m in v["mismatches"]]
    if "fill" in x:
        f = x["fill"]
        lines.append(f"fill ({f['cell']}): " + ", ".join(f"{k} {f['before'][k] * 100:.1f} -> {f['after'][k] * 100:.1f} %"
                                                        for k in f["before"]))
    lines += foundry_lines(x)
    return "\n".join(lines)


@main.command()
@design_arg
@out_opt("output folder (default: reports/<design>/layout)", folder=True)
@click.option("--rows", type=click.IntRange(1, 1000), default=2, show_default=True)
@click.option("--cols", type=click.IntRange(1, 1000), default=2, show_default=True)
@click.option("--drc", is_flag=True, help="run the technology's DRC deck (KLayout batch) on the dual pixel "
              "with its columns; exit 1 when it finds a violation")
@click.option("--lvs", is_flag=True, help="compare the layout's extracted netlist with the kit's netlist "
              "(KLayout Python API); exit 1 on a mismatch")
@click.option("--foundry-lvs", is_flag=True, help="also run the foundry's LVS deck (fd_pv, deep mode; fetched by "
              "setup.sh where github.com is reachable): exit 1 on a mismatch, 5 when the deck is not installed")
@click.option("--density", is_flag=True, help="the foundry's density deck on the chip (fd_pv): exit 1 on a "
              "violation, 5 when the deck is not installed")
@click.option("--antenna", is_flag=True, help="the foundry's antenna deck on the chip (fd_pv): exit 1 on a "
              "violation, 5 when the deck is not installed")
@click.option("--fill", is_flag=True, help="dummy fill on every layer under the foundry's density figure, kept "
              "off the light path (the chip then passes --density)")
@click.option("--afe", is_flag=True, help="draw every column's AFE (switched capacitors, MIM capacitors, "
              "op-amp) under its column circuit")
@click.option("--shield", type=click.Choice(["full", "pixels", "none"]), default="full", show_default=True,
              help="top-metal light shield: everything but the openings, the pixels only (the readout left "
              "open), or none")
@click.option("--pictures/--no-pictures", default=True, show_default=True, help="2D and 3D pictures")
@click.option("--golden", is_flag=True, help="(re)write layouts/golden/<design>.gds, the geometry baseline")
@json_opt
def layout(design, out, rows, cols, drc, lvs, foundry_lvs, density, antenna, fill, afe, shield, pictures, golden, as_json):
    """Write the GDS (an R x C array with its column circuits, --afe its AFEs, the light shield) and
    each cell's SPICE netlist, extract PD area / perimeter / photoactive area and the junction
    the shield leaves open per block, draw 2D and 3D views; --drc / --lvs sign the array off. A pixel4t
    design: its one 4T cell and LVS netlist, --drc / --lvs / --foundry-lvs its sign-off (docs/pixel4t.md)."""
    from ..family import ROLE_FAMILIES, family_of
    from ..layout.fit import as_config_error
    from ..layout.flow import layout_design, verdict, write_gds
    from ..layout.library import build_library
    from ..layout.rules import RuleError
    fam = family_of(design)
    if fam in ROLE_FAMILIES:   # one 4T cell (layout.pixel4t); a designer's netlist: their own GDS
        return _layout_role(design, fam, out, drc, lvs, foundry_lvs, dict(density=density, antenna=antenna, fill=fill,
                                                                        afe=afe, golden=golden), as_json)
    d = load(design, drawable=False)
    for opt, n, field in (("--rows", rows, "rows"), ("--cols", cols, "cols")):
        most = getattr(d.primary, field)
        if n > most:   # the chip the design describes bounds the array
            raise ConfigError("command line", opt, n, f"1 to {most} (the design's primary.{field})")
    try:
        if golden:
            path = write_gds(build_library(d, 2, 2), Path("layouts/golden") / f"{d.name}.gds")
            emit({"gds": str(path)}, as_json, lambda x: f"wrote {x['gds']}")
            return
        r = layout_design(d, output_path(out, d, "layout"), rows, cols, pictures=pictures, drc=drc, lvs=lvs,
                          afe=afe, shield=shield, foundry_lvs=foundry_lvs, density=density, antenna=antenna,
                          fill=fill)
    except RuleError as exc:
        raise as_config_error(d, exc) from None
    emit(r, as_json, _render)
    status = verdict(r)
    if status:
        sys.exit(status)


def _layout_role(design, fam, out, drc, lvs, foundry_lvs, chip_options: dict, as_json) -> None:
    """``pixelkit layout`` of a pixel read by role: the 4T cell, its LVS netlist and its sign-off."""
    from ..family import load_family_design
    from ..layout.pixel4t import layout_pixel4t
    from ..layout.route import RouteError
    from ..layout.rules import RuleError
    if fam != "pixel4t":
        raise ConfigError(design, "family", fam, "a pixel4t design (a pixel from a netlist has no layout the kit "
                          "draws: sign off your own GDS with pixelkit signoff GDS --netlist FILE)")
    for name, asked in chip_options.items():
        if asked:
            raise ConfigError("command line", f"--{name}", True, "not with a pixel4t design (the kit draws one 4T "
                              "cell: no array, column circuits or AFE)")
    d = load_family_design(design, fam)
    try:
        r = layout_pixel4t(d, output_path(out, d, "layout"), drc=drc, lvs=lvs, foundry_lvs=foundry_lvs)
    except (RuleError, RouteError) as exc:   # the cell does not fit: name the 4T design's own field
        field = (getattr(exc, "field", "") or "").replace("pixel.devices.", "devices.").replace("primary.pd_", "pixel.ppd_")
        raise ConfigError(design, field or "pixel.pitch", exc.value if field else d.pixel.pitch,
                          f"a value the 4T cell fits ({exc})") from None
    emit(r, as_json, _render_role)
    if r["exit_status"]:
        sys.exit(r["exit_status"])


def _render_role(x: dict) -> str:
    lines = [f"wrote {x['gds']} (cell {x['top']}, {x['pitch_um']:g} um) and {x['spice']}",
             f"photodiode: {x['photodiode']}"]
    s = x.get("signoff")
    if s:
        lines.append(signoff_text(s))
    return "\n".join(lines)
