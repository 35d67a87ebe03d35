"""``pixelkit report``: the design report of a chip revision, with the revision diff."""
from __future__ import annotations

import sys
from pathlib import Path

import click

from .types import FilePath

from .common import (design_arg, emit, finishing, json_opt, load_role, main, out_checked, post_layout_opt,
                     quiet_opt, view)


@main.command("report")
@design_arg
@click.option("--out", type=FilePath(file_okay=False), default=None, callback=out_checked(True),
              help="report folder (default reports/<design>)")
@click.option("--baseline", type=FilePath(file_okay=False), default=None,
              help="an earlier report folder: add the revision diff, ranked by the margin each spec used; exit 1 "
                   "when a spec newly fails (a design without [spec]: when a checked figure moved)")
@click.option("--measured", type=FilePath(dir_okay=False), default=None,
              help="measured data (CSV, as 'pixelkit gap diagnose' reads) for the sim-to-real section")
@click.option("--quick", is_flag=True, help="nominal only: the sign-off at the nominal condition alone (no corners, "
              "no Monte Carlo; its verdict says so), fewer sweep points, no sensitivity table")
@click.option("--waves", default=None, metavar="SPEC,SPEC,...|all",
              help="show these specs' waveforms too (worst condition against nominal); every failing spec's "
                   "is shown anyway")
@click.option("--exhaustive", is_flag=True,
              help="no early stop: the sign-off's Monte Carlo runs every [verify] mc sample (the default stops "
                   "once every yield is decided against min_yield; docs/verify.md)")
@click.option("--no-cache", is_flag=True, help="rebuild every section (SPICE runs and the foundry DRC still use their caches)")
@click.option("--backend", type=click.Choice(["batch", "shared"]), default="batch", show_default=True)
@click.option("--jobs", type=click.IntRange(1, 64), default=None, help="parallel ngspice workers")
@quiet_opt
@post_layout_opt
@json_opt
def report(design, out, baseline, measured, quick, exhaustive, waves, no_cache, backend, jobs, as_json):
    """Write the design report (HTML + CSV/JSON + summary.json); with --baseline, the revision diff.
    Exit 1 when a spec fails (or the diff does), 5 when nothing fails but something was not measured."""
    from ..design import load_design
    from ..family import ROLE_FAMILIES, family_of
    from ..report.build import build_report
    from ..report.text import report_text
    fam, registry = family_of(design), None
    if fam in ROLE_FAMILIES:   # a pixel read by role: its sign-off and its figures (report.sections.ROLE_REGISTRY)
        from ..errors import ConfigError
        from ..report.sections import ROLE_REGISTRY
        if measured is not None:
            raise ConfigError(design, "--measured", str(measured), f"no --measured for a {fam} design (the gap "
                              "diagnosis of a pixel read by role is not written yet)")
        d, registry = load_role(design, fam, "report"), ROLE_REGISTRY   # the 4T with --post-layout: its view
    else:
        d = view(load_design(design))
    out = Path(out) if out else Path("reports") / d.name
    chosen = _waves(d, waves)
    r = build_report(d, out, quick=quick, backend=backend, jobs=jobs, measured=measured, baseline=baseline,
                     use_cache=not no_cache, html=not as_json, waves=chosen,
                     exhaustive=exhaustive, registry=registry)
    finishing()  # the report is in place: a Ctrl-C from here no longer calls the run interrupted
    data = {"out": r["out"], "html": r["html"], "failed_sections": r["failed"], **r["summary"]}
    if "diff" in r:
        data["diff"] = r["diff"]
    emit(data, as_json, report_text)
    code = r["summary"]["verdict"]["exit"]   # report.verdict: the rule verify follows (errors.verdict_exit)
    if code:
        sys.exit(code)


def _waves(design, value) -> tuple:
    """The specs named by ``--waves`` (``all``: every spec), refused naming the unknown one."""
    if value is None:
        return ()
    from ..errors import ConfigError
    names = [x.strip() for x in value.split(",") if x.strip()]
    have = [s.name for s in design.spec]
    if names == ["all"]:
        return tuple(have)
    unknown = [x for x in names if x not in have]
    if unknown or not names:
        raise ConfigError("report", "--waves", value, "'all' or specs of the design's [spec] table: "
                          + (", ".join(have) or "(it has none)"))
    return tuple(names)
