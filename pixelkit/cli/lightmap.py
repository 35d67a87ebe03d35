"""``pixelkit lightmap``: the junctions the shield leaves open, their photocurrent, the output error."""
from __future__ import annotations

import click

from .common import design_arg, emit, json_opt, load, main, spice_opts


def _text(r: dict) -> str:
    lines = [f"light map, shield {r['shield']}, {r['light']} light, {r['irradiance_W_m2']:g} W/m2 on the die:",
             f"  {'cell':11s} {'net':12s} {'bench node':12s} {'junction':26s} {'area (um2)':>10s} {'I (pA)':>9s}"]
    for j in r["junctions"]:
        lines.append(f"  {j['cell']:11s} {j['net']:12s} {j['node']:12s} {j['kind']:26s} {j['area_m2'] * 1e12:10.3f} "
                     f"{j['current_A'] * 1e12:9.3f}")
    lines.append(f"  readout junctions exposed: {r['readout_area_m2'] * 1e12:.3f} um2")
    v = r["verdict"]
    lines.insert(0, f"{v['verdict']}: AFE output error against {v['limit']}"
                 + (" the read noise" if v["limit_kind"] != "V" else "") + " in every column"
                 + (f" (beyond it: {', '.join(v['failed'])})" if v["failed"] else ""))
    for c, v in r["columns"].items():
        lines.append(f"  {c}: AFE output error {v['error_V'] * 1e3:+.3f} mV, {v['error_over_noise']:.2g} x the read "
                     f"noise there ({v['read_noise_V'] * 1e3:.3f} mV; lit from the dark state through the exposures); from the row on "
                     f"{v['error_from_row_V'] * 1e3:+.3f} mV ({v['error_from_row_over_noise']:.2g} x); limit "
                     f"{r['verdict']['columns'][c]['limit_V'] * 1e3:.3f} mV: {r['verdict']['columns'][c]['status'].upper()}")
    return "\n".join(lines)


@main.command("lightmap")
@design_arg
@click.option("--shield", type=click.Choice(["pixels", "full"]), default="pixels", show_default=True,
              help="pixels: the shield as drawn over the subpixels, the readout open ([Thesis2019]'s chip); "
                   "full: only the pixels' light openings see light")
@click.option("--light", type=click.Choice(["geometric", "modelled"]), default=None,
              help="the junctions' currents: geometric (open area x the technology's QE) or modelled (the collection "
                   "model of each readout cell, docs/light-collection.md) [default: the design's light.model]")
@click.option("--max-error", default=None, metavar="KX|VOLTAGE",
              help="the limit of each column's AFE output error: a multiple of the read noise there ('1x') or a "
                   "voltage ('2 mV'); exit 1 beyond it [default: the design's light.max_readout_error, '1x' "
                   "unless it says otherwise]")
@spice_opts
@json_opt
def lightmap_cmd(design, shield, light, max_error, backend, jobs, as_json):
    """Exposed junctions of the drawn dual pixel and its column circuits, their photocurrent at the
    scene's headlight irradiance, and the AFE output error each array's column sees (SPICE), judged
    against the design's limit ([light] max_readout_error) or --max-error: exit 1 when a column's error
    is beyond it."""
    from ..layout.pex.light import light_map
    from ..tech.stack import require_stack
    from ..verify.light import judge, parse_limit
    if max_error is not None:
        parse_limit(max_error)   # refused before any run
    d = load(design)
    require_stack(d.tech, "the light map")
    if light == "modelled":
        from ..layout.pex.collection import require
        require(d)   # a technology without [collection]: refused naming it, before any run
    r = light_map(d, shield, backend, light=light)
    r["verdict"] = judge(r["columns"], max_error if max_error is not None else d.light.max_readout_error)
    emit(r, as_json, _text)
    if r["verdict"]["exit"]:
        raise SystemExit(r["verdict"]["exit"])
