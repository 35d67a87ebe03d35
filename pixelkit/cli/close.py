"""``pixelkit close``: move the [close] knobs until every spec passes at every condition (docs/close.md)."""
from __future__ import annotations

import click

from .common import (design_arg, emit, finishing, json_opt, load, main, out_opt, output_path, post_layout_opt,
                     scheduler_address, spice_opts)

@main.command("close")
@design_arg
@out_opt("the closed revision's design file (default reports/<design>/close/<design>_closed.toml); "
         "the path goes beside it as <name>.close.json")
@click.option("--scheduler", default=None, callback=scheduler_address,
              help="Dask scheduler address (default: local workers)")
@post_layout_opt
@spice_opts
@json_opt
def close_cmd(design, out, scheduler, backend, jobs, as_json):
    """Find the revision that passes every [spec] at every condition of the [verify] grid (with its
    Monte Carlo yield) by moving the [close] knobs; exit 1 naming the specs that conflict when none does."""
    from ..close.output import text
    from ..close.revision import close_design
    from ..errors import EXIT_REGRESSION, verdict_exit
    from ..progress import enabled
    from ..spice.counter import spice_progress
    from ..family import ROLE_FAMILIES, family_of
    fam = family_of(design)
    if fam in ROLE_FAMILIES:   # a pixel read by role: its own figures and suite (rolepix), close's loop
        from .common import load_role
        d = load_role(design, fam, "close")    # with --post-layout the 4T's extraction, redrawn per candidate
    else:
        d = load(design)
    path = output_path(out, d, f"close/{d.name}_closed.toml")
    show = enabled() and not as_json

    def say(line: str) -> None:
        if show:
            from tqdm import tqdm
            tqdm.write(line, file=click.get_text_stream("stderr"))

    with spice_progress("close") as bar:
        def tell(stage: str) -> None:
            bar.set_description_str(f"close: {stage}", refresh=True)
        r = close_design(d, path, backend=backend, jobs=jobs, scheduler=scheduler, tell=tell, say=say)
    finishing()
    r = {k: v for k, v in r.items() if k not in ("design_obj",)}
    emit(r, as_json, text)
    if not r["passes"] and r["status"] != "not measured":
        reason = r.get("conflict", {}).get("text") or r["status"]
        click.echo(f"pixelkit: close: {r['status']}: {reason}", err=True)
        raise SystemExit(EXIT_REGRESSION)
    so = r["signoff"] or {"rows": [], "errors": []}   # the revision's sign-off: the team's rule (1 > 4 > 5 > 0)
    code = verdict_exit([row["status"] for row in so["rows"]], bool(so["errors"]))
    if code:
        raise SystemExit(code)
