"""``pixelkit mc``: Monte Carlo mismatch of an array frame -> DSNU, PRNU, column FPN, pedestal."""
from __future__ import annotations

import json

import click

from .common import design_arg, emit, json_opt, load, main, out_opt, output_path, scheduler_address, spice_opts


@main.command("mc")
@design_arg
@click.option("--rows", type=click.IntRange(2, 27), default=6, show_default=True)
@click.option("--cols", type=click.IntRange(2, 50), default=4, show_default=True)
@click.option("--seed", type=click.IntRange(0, 2**31 - 1), default=1, show_default=True,
              help="one seed = one chip; the same seed gives the same numbers")
@click.option("--corner", "corners", multiple=True, help="process corner(s) to run (default: the design's)")
@click.option("--afe", "with_afe", is_flag=True, help="include the column AFEs (column FPN at the AFE output)")
@click.option("--scheduler", default=None, callback=scheduler_address, help="Dask scheduler address (default: local workers)")
@out_opt("folder for mc.json (default reports/<design>/mc)", folder=True)
@spice_opts
@json_opt
def mc_cmd(design, rows, cols, seed, corners, with_afe, scheduler, out, backend, jobs, as_json):
    """Fixed-pattern figures of one Monte Carlo chip (GF180 statistical models), per corner."""
    from ..fileio import write_atomic
    from ..mc.montecarlo import run_monte_carlo
    from ..sweep.space import design_with
    d = load(design)
    runs = []
    for corner in corners or (d.corner_name,):
        dc = design_with(d, {"corner": corner}) if corner != d.corner_name else d
        runs.append(run_monte_carlo(dc, rows, cols, seed, with_afe, backend, jobs, scheduler))
    folder = output_path(out, d, "mc")
    from ..fileio import out_folder
    out_folder(folder)   # checked: a link, a file or a device there is refused (fileio)
    write_atomic(folder / "mc.json", json.dumps(runs, indent=1))
    summary = [{"corner": r["corner"], **{f"{k}_{f}": r[k][f] for k in ("primary", "secondary")
                                          for f in ("pedestal_V", "dsnu_V", "prnu_pct", "column_fpn_V", "offset_fpn_V")},
                "secondary_target_over_dsnu": r["secondary"]["target_over_dsnu"],
                "pelgrom_offset_fpn_V": r["pelgrom"]["sigma_reset_V"],
                "measured_offset_fpn_V": r["pelgrom"]["measured_offset_fpn_V"]} for r in runs]
    data = {"seed": seed, "rows": rows, "cols": cols, "runs": summary, "json": str(folder / "mc.json"),
            "failures": [f for r in runs for f in r["failures"]]}

    def text(x):
        lines = [f"Monte Carlo chip seed {x['seed']}, {x['rows']} x {x['cols']} dual pixels"]
        for s in x["runs"]:
            lines.append(f"corner {s['corner']}:")
            for k in ("primary", "secondary"):
                lines.append(f"  {k:9s} pedestal (chip mean) {s[f'{k}_pedestal_V'] * 1e3:7.2f} mV  "
                             f"DSNU {s[f'{k}_dsnu_V'] * 1e3:6.3f} mV"
                             f"  PRNU {s[f'{k}_prnu_pct']:5.2f} %  column FPN {s[f'{k}_column_fpn_V'] * 1e3:6.3f} mV"
                             f"  offset FPN (before DS) {s[f'{k}_offset_fpn_V'] * 1e3:5.2f} mV")
            lines.append(f"  secondary 5 % target / DSNU = {s['secondary_target_over_dsnu']:.0f}; offset FPN "
                         f"{s['measured_offset_fpn_V'] * 1e3:.2f} mV vs Pelgrom {s['pelgrom_offset_fpn_V'] * 1e3:.2f} mV")
        lines.append("DSNU: pixel sigma of the dark frame after double sampling, every device drawn from the "
                     "models' statistics (SPICE); pedestal: the dark frame's mean output (switch charge injection "
                     "and feedthrough, not dark current)")
        lines.append(f"details: {x['json']}")
        return "\n".join(lines)
    emit(data, as_json, text)
    if data["failures"]:
        raise SystemExit(4)
