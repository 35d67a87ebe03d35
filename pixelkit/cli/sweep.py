"""``pixelkit sweep``: any design parameter, stimulus or simulator option over a grid."""
from __future__ import annotations

import click

from .common import design_arg, emit, json_opt, load, main, out_opt, output_path, scheduler_address, spice_opts, post_layout_opt


@main.command("sweep")
@design_arg
@click.option("--over", "overs", multiple=True, required=True, metavar="NAME=VALUES",
              help="an axis (repeat for a grid): pixel.sf_bias=300nA,400nA | iph_p=log:10p:2n:8 | "
                   "corner=tt,ff,ss | temperature=0degC,85degC | option.reltol=1e-4,1e-5")
@click.option("--afe", "with_afe", is_flag=True, help="read through the SC AFEs too (afe_*_V figures)")
@click.option("--scheduler", default=None, callback=scheduler_address,
              help="Dask distributed scheduler address (tcp://host:8786); default: local worker processes")
@out_opt("folder for sweep.csv and sweep.nc (default reports/<design>/sweep)", folder=True)
@spice_opts
@post_layout_opt
@json_opt
def sweep_cmd(design, overs, with_afe, scheduler, out, backend, jobs, as_json):
    """Sweep the dual-pixel bench; failed points are listed with ngspice's message.

    Re-running the same sweep after an interruption recomputes only the unfinished
    points (the others come from the simulation cache)."""
    from ..fileio import write_atomic
    from ..sweep.run import run_sweep
    from ..sweep.space import parse_axis
    d = load(design)
    axes = [parse_axis(o) for o in overs]
    s = run_sweep(d, axes, with_afe=with_afe, backend=backend, jobs=jobs, scheduler=scheduler)
    folder = output_path(out, d, "sweep")
    from ..fileio import out_folder
    out_folder(folder)   # checked: a link, a file or a device there is refused (fileio)
    write_atomic(folder / "sweep.csv", s.table())
    nc = folder / "sweep.nc"
    write_atomic(nc, bytes(s.dataset.assign(message=s.dataset["message"].astype(str)).to_netcdf()))
    data = {"points": s.points, "failed": len(s.failures), "computed": sum(not p["cached"] for p in s.points),
            "wall_s": s.wall_s, "csv": str(folder / "sweep.csv"), "netcdf": str(nc)}

    def text(x):
        lines = [f"{len(x['points'])} points ({x['computed']} simulated, the rest from the cache), "
                 f"{x['failed']} failed, {x['wall_s']:.1f} s", f"table: {x['csv']}", f"xarray: {x['netcdf']}"]
        lines += [f"FAILED {_label(p, axes)}: {p['message']}" for p in x["points"] if not p["ok"]]
        return "\n".join(lines)
    emit(data, as_json, text)
    if s.failures:
        raise SystemExit(4)


def _label(point, axes) -> str:
    return ", ".join(f"{a.name}={point[a.name]}" for a in axes)
