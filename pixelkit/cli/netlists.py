"""``pixelkit netlist | netlists | regress``: runnable decks, golden netlists, regression."""
from __future__ import annotations

import sys
from pathlib import Path

import click

from .types import FilePath

from ..errors import EXIT_REGRESSION
from .common import design_arg, emit, json_opt, load, main, out_opt, output_path, spice_opts, post_layout_opt

REFERENCE = "designs/dual_pixel_revA.toml"


@main.command()
@design_arg
@click.option("--bench", "bench_name", default="bench_dual_pixel", show_default=True,
              help="a deck that runs alone (pixelkit netlists lists them as 'bench')")
@out_opt("deck file (default: reports/<design>/<bench>.cir)")
@click.option("--models", "models_mode", type=click.Choice(["absolute", "link"]), default="absolute",
              show_default=True, help="absolute model paths, or 'models/<file>' with a 'models' link "
                                      "written beside the deck")
@post_layout_opt
@json_opt
def netlist(design, bench_name, out, models_mode, as_json):
    """Write a deck that runs as it is in `ngspice -b`: the kit's options, models, stimulus."""
    from ..api import export_deck
    from ..family import ROLE_FAMILIES, family_of, load_family_design
    fam = family_of(design)
    if fam in ROLE_FAMILIES:   # a pixel read by role: its own benches (rolepix.signal.export_benches)
        from ..errors import ConfigError
        from ..rolepix.export import export_benches
        from ..spice.export import export_deck as write_deck
        d = load_family_design(design, fam)
        benches = export_benches(d)
        name = "cds" if bench_name == "bench_dual_pixel" else bench_name
        if name not in benches:
            raise ConfigError(design, "--bench", bench_name, f"one of {', '.join(benches)} (a {fam} design)")
        path = write_deck(benches[name](), output_path(out, d, f"{name}.cir"), models=models_mode)
        emit({"design": d.name, "bench": name, "deck": str(path), "run_with": f"ngspice -b {path}"},
             as_json, lambda x: f"wrote {x['deck']} (run: {x['run_with']})")
        return
    d = load(design)
    path = export_deck(d, bench_name, output_path(out, d, f"{bench_name}.cir"), models=models_mode)
    emit({"design": d.name, "bench": bench_name, "deck": str(path), "run_with": f"ngspice -b {path}"},
         as_json, lambda x: f"wrote {x['deck']} (run: {x['run_with']})")


@main.command()
@click.argument("design", type=FilePath(dir_okay=False), required=False, default=REFERENCE)
@click.option("--write", is_flag=True, help="regenerate the golden netlists in --out")
@out_opt("folder of the golden netlists (default: netlists)", folder=True)
@json_opt
def netlists(design, write, out, as_json):
    """List the generators, or regenerate their golden netlists (DESIGN: the reference design)."""
    from ..registry import BENCHES, GENERATORS, write_all
    if write:
        paths = [str(p) for p in write_all(load(design), Path(out or "netlists"))]
        emit({"written": paths}, as_json, lambda x: "\n".join(f"wrote {p}" for p in x["written"]))
    else:
        emit({"generators": list(GENERATORS), "benches": list(BENCHES)}, as_json,
             lambda x: "\n".join(f"{g:<22}{'bench (runs alone: netlist --bench)' if g in x['benches'] else 'cells'}"
                                  for g in x["generators"]))


@main.command()
@design_arg
@click.option("--baseline", type=FilePath(dir_okay=False), required=True, help="baseline JSON file")
@click.option("--update", is_flag=True, help="measure and store the baseline instead of comparing")
@spice_opts
@json_opt
def regress(design, baseline, update, backend, jobs, as_json):
    """Compare a design's measured figures with a baseline; exit 1 when something changed."""
    from ..api import experiment
    from ..family import DEFAULT, family_of, run_family
    from ..regress import compare, load_baseline, make_baseline, save_baseline
    fam = family_of(design)
    base = None if update else load_baseline(Path(baseline))   # a bad baseline is found before the runs
    if fam == DEFAULT:
        result = experiment(load(design), backend=backend, jobs=jobs)
    else:  # another pixel family: its own experiment and figures
        result = run_family(design, fam, backend=backend, jobs=jobs)
    name = result["design"]
    if update:
        save_baseline(Path(baseline), make_baseline(name, result))
        emit({"baseline": baseline, "written": True}, as_json, lambda x: f"baseline written: {x['baseline']}")
        return
    rows = compare(base, result)
    changed = [r for r in rows if r["changed"]]
    emit({"design": name, "baseline": baseline, "changed": changed, "figures": rows}, as_json, _regress_text)
    if changed:
        sys.exit(EXIT_REGRESSION)


def _regress_text(data) -> str:
    lines = [f"regression of {data['design']} against {data['baseline']}:"]
    for r in data["figures"]:
        mark = "CHANGED" if r["changed"] else "ok"
        new = "missing" if r["new"] is None else f"{r['new']:.6g}"
        lines.append(f"  {mark:<8}{r['figure']:<32} {r['old']:.6g} -> {new}")
    lines.append(f"{len(data['changed'])} figure(s) beyond tolerance")
    return "\n".join(lines)
