"""``pixelkit netlists | regress``: golden netlists and regression against a baseline."""
from __future__ import annotations

import sys
from pathlib import Path

import click

from .common import design_arg, emit, json_opt, main


@main.command()
@click.option("--write", is_flag=True, help="regenerate the golden netlists in --out")
@click.option("--out", type=click.Path(file_okay=False), default="netlists", show_default=True)
@click.option("--design", "design_path", type=click.Path(dir_okay=False),
              default="designs/dual_pixel_revA.toml", show_default=True)
def netlists(write, out, design_path):
    """List the generators, or regenerate their golden netlists."""
    from ..circuits.registry import GENERATORS, write_all
    from ..design import load_design
    if write:
        for p in write_all(load_design(design_path), Path(out)):
            click.echo(f"wrote {p}")
    else:
        click.echo("\n".join(GENERATORS))


@main.command()
@design_arg
@click.option("--baseline", type=click.Path(dir_okay=False), required=True, help="baseline JSON file")
@click.option("--update", is_flag=True, help="measure and store the baseline instead of comparing")
@click.option("--backend", type=click.Choice(["batch", "shared"]), default="batch", show_default=True)
@json_opt
def regress(design, baseline, update, backend, as_json):
    """Compare a design's measured figures with a baseline; exit 1 when something changed."""
    from ..design import load_design
    from ..experiments.thesis import run_experiment
    from ..regress import compare, load_baseline, make_baseline, save_baseline
    d = load_design(design)
    result = run_experiment(d, backend=backend)
    if update:
        save_baseline(Path(baseline), make_baseline(d.name, result))
        click.echo(f"baseline written: {baseline}")
        return
    rows = compare(load_baseline(Path(baseline)), result)
    changed = [r for r in rows if r["changed"]]
    emit({"design": d.name, "baseline": baseline, "changed": changed, "figures": rows}, as_json, _regress_text)
    if changed:
        sys.exit(1)


def _regress_text(data) -> str:
    lines = [f"regression of {data['design']} against {data['baseline']}:"]
    for r in data["figures"]:
        mark = "CHANGED" if r["changed"] else "ok"
        new = "missing" if r["new"] is None else f"{r['new']:.6g}"
        lines.append(f"  {mark:<8}{r['figure']:<32} {r['old']:.6g} -> {new}")
    lines.append(f"{len(data['changed'])} figure(s) beyond tolerance")
    return "\n".join(lines)
