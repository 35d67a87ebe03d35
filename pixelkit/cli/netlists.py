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
@click.option("--schematic", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="also draw the bench (with --bench cell: the pixel's subcircuit) as an Xschem schematic "
                   "FILE.sch, its pk_*.sym symbols beside it (docs/netlist-benches.md)")
@post_layout_opt
@json_opt
def netlist(design, bench_name, out, models_mode, schematic, as_json):
    """Write a deck that runs as it is in `ngspice -b`: the kit's options, models, stimulus."""
    from ..family import ROLE_FAMILIES, family_of
    from ..spice.export import export_deck as write_deck
    if schematic is not None and schematic.suffix != ".sch":
        from ..errors import ConfigError
        raise ConfigError(design, "--schematic", str(schematic), "an Xschem schematic file name ending in .sch")
    fam = family_of(design)
    if fam in ROLE_FAMILIES:   # a pixel read by role: its own benches (rolepix.export)
        from ..errors import ConfigError
        from ..rolepix.export import export_benches
        from .common import load_role
        d = load_role(design, fam, "netlist")   # the 4T with --post-layout: its drawn cell's wiring as Cpex*
        benches = export_benches(d)
        name = "cds" if bench_name == "bench_dual_pixel" else bench_name
        if name not in benches:
            raise ConfigError(design, "--bench", bench_name, f"one of {', '.join(benches)} (a {fam} design)")
        net = benches[name]()
    else:
        from ..api import bench
        from ..registry import require_bench
        d, name = load(design), bench_name
        require_bench(name)
        net = bench(d, name)
    path = write_deck(net, output_path(out, d, f"{name}.cir"), models=models_mode)
    row = {"design": d.name, "bench": name, "deck": str(path), "run_with": f"ngspice -b {path}"}
    if schematic is not None:
        row["schematic"] = str(draw(net, schematic))
    emit(row, as_json, lambda x: f"wrote {x['deck']} (run: {x['run_with']})"
         + (f"; schematic {x['schematic']}" if "schematic" in x else ""))


def draw(net, path):
    """The bench drawn (a deck without top-level elements, such as a cell: its last subcircuit)."""
    from ..spice.export import deck_text
    from ..spice.schematic import deck_schematic, subckt_schematic
    if not net.elements and net.subckts:
        return subckt_schematic(net.subckts[-1], path, support=net.subckts[:-1], models=net.models)
    return deck_schematic(net, deck_text(net, "absolute"), path)


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
