"""``pixelkit verify``: every spec over the PVT grid and its Monte Carlo yield; the sign-off table."""
from __future__ import annotations

import click

from .common import design_arg, emit, json_opt, load, main, out_opt, output_path, post_layout_opt, scheduler_address, spice_opts


def _list(kind: str):
    def parse(ctx, param, value):
        if value is None:
            return None
        from ..errors import ConfigError
        from ..units import quantity
        items = [v.strip() for v in value.split(",") if v.strip()]
        if not items:
            raise ConfigError("verify", param.opts[0], value, "a comma-separated list")
        if kind == "corner":
            return tuple(items)
        dim = "K" if kind == "temperature" else "1"
        out = tuple(quantity(v, dim, param.opts[0], "verify") for v in items)
        if kind == "supply" and any(not -0.5 <= s <= 0.5 for s in out):
            raise ConfigError("verify", param.opts[0], value, "supply deviations from -50 % to +50 %")
        if kind == "temperature" and any(not 213.15 <= t <= 473.15 for t in out):
            raise ConfigError("verify", param.opts[0], value, "temperatures from -60 degC to 200 degC")
        return out
    return parse


@main.command("verify")
@design_arg
@click.option("--corners", callback=_list("corner"), default=None, metavar="C,C,...",
              help="process corners (default: [verify] corners, else every corner of the model library)")
@click.option("--temperatures", callback=_list("temperature"), default=None, metavar="T,T,...",
              help="die temperatures, like -20degC,27degC,85degC (default: [verify] temperatures)")
@click.option("--supplies", callback=_list("supply"), default=None, metavar="S,S,...",
              help="supply deviations, like -10%,0%,10% (default: [verify] supplies)")
@click.option("--mc", type=click.IntRange(0, 100000), default=None,
              help="Monte Carlo samples at the nominal condition (default: [verify] mc)")
@click.option("--seed", type=click.IntRange(0, 2**31 - 1), default=None, help="Monte Carlo seed (default: [verify] seed)")
@click.option("--mc-full", is_flag=True, default=False,
              help="run every Monte Carlo sample (default: stop once every yield is decided against "
                   "[verify] min_yield; docs/verify.md)")
@post_layout_opt
@click.option("--scheduler", default=None, callback=scheduler_address,
              help="Dask scheduler address (default: local workers)")
@out_opt("folder for signoff.csv and signoff.json (default reports/<design>/verify)", folder=True)
@spice_opts
@json_opt
def verify_cmd(design, corners, temperatures, supplies, mc, seed, mc_full, scheduler, out, backend, jobs, as_json):
    """Sign-off: every [spec] at every corner x temperature x supply, Monte Carlo yield; exit 1 on a failing spec,
    5 when none fails but one was not measured everywhere (4: a simulation failed)."""
    import csv
    import io
    import json

    from ..errors import EXIT_NOT_MEASURED
    from ..fileio import json_default, write_atomic
    from ..verify.run import verify
    from ..verify.signoff import COLUMNS, csv_rows, exit_status, not_measured, text, where
    from ..errors import ConfigError
    from ..family import ROLE_FAMILIES, family_of
    fam = family_of(design)
    if fam in ROLE_FAMILIES:   # a pixel read by role: its own figures, verify's run (rolepix.suite)
        from .common import load_role
        d = load_role(design, fam, "verify")   # with --post-layout the 4T's drawn cell's extraction
    elif fam == "ratio":   # its own figures (docs/verify.md); a WDR design is refused by load
        from ..families.ratio.design import load_ratio_design
        from ..families.ratio.signoff import verify
        if click.get_current_context().meta.get("pixelkit.post_layout"):
            raise ConfigError("verify", "--post-layout", True, "a dual-pixel design (the ratio family has no layout)")
        d = load_ratio_design(design)
    else:
        d = load(design)   # with --post-layout: its post-layout view
    folder = output_path(out, d, "verify")
    kw = {"mc_full": True} if mc_full else {}   # the ratio family's verify has no Monte Carlo
    r = verify(d, corners, temperatures, supplies, mc, seed, backend=backend, jobs=jobs, scheduler=scheduler, **kw)
    from ..fileio import out_folder
    out_folder(folder)   # checked: a link, a file or a device there is refused (fileio)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    w.writerows(csv_rows(r["rows"]))
    write_atomic(folder / "signoff.csv", buf.getvalue())
    write_atomic(folder / "signoff.json", json.dumps(r, indent=1, default=json_default) + "\n")
    r = {**r, "csv": str(folder / "signoff.csv"), "json": str(folder / "signoff.json")}
    summary = {k: v for k, v in r.items() if k not in ("raw", "conditions", "mc_values")}
    emit(summary, as_json, lambda x: text(x) + f"\ntable: {x['csv']}\ndetails: {x['json']}")
    status = exit_status(r)   # the team's rule (pixelkit.errors.verdict_exit): 1 > 4 > 5 > 0
    if r["failed"]:
        names = "; ".join(f"{row['spec']} {where(row)}" for row in r["rows"] if row["status"] == "fail")
        click.echo(f"pixelkit: verify: {len(r['failed'])} spec(s) fail: {names}", err=True)
    elif status == EXIT_NOT_MEASURED:
        click.echo(f"pixelkit: verify: nothing failed, but not measured (exit {status}): "
                   + "; ".join(not_measured(r)), err=True)
    if status:
        raise SystemExit(status)
