"""Subcommands beyond the core ones: netlists, regress, array, size, layout."""
from __future__ import annotations

import sys
from pathlib import Path

import click

from .cli import design_arg, emit, json_opt, main


@main.command()
@click.option("--write", is_flag=True, help="regenerate the golden netlists in --out")
@click.option("--out", type=click.Path(file_okay=False), default="netlists", show_default=True)
@click.option("--design", "design_path", type=click.Path(dir_okay=False),
              default="designs/dual_pixel_revA.toml", show_default=True)
def netlists(write, out, design_path):
    """List the generators, or regenerate their golden netlists."""
    from .circuits.registry import GENERATORS, write_all
    from .design import load_design
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
    from .design import load_design
    from .experiments.thesis import run_experiment
    from .regress import compare, load_baseline, make_baseline, save_baseline
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


@main.command("array")
@design_arg
@click.option("--rows", type=click.IntRange(1, 27), default=2, show_default=True)
@click.option("--cols", type=click.IntRange(1, 50), default=2, show_default=True)
@click.option("--out", type=click.Path(dir_okay=False), default=None, help="PNG of the readout waveforms")
@json_opt
def array_cmd(design, rows, cols, out, as_json):
    """Simulate an array read row by row (fig. 3.13); one photocurrent per subpixel."""
    from .circuits.testbench import array_bench, timings
    from .design import load_design
    from .measure.pixel import double_sampled
    from .plots.waveforms import plot_columns
    from .spice import simulate
    d = load_design(design)
    n = d.secondary_per_pixel
    # distinct photocurrents so that every subpixel is told apart (as in fig. 3.13)
    ip = [[0.2e-9 * (1 + r * cols + c) for c in range(cols)] for r in range(rows)]
    is_ = [[10e-12 * (1 + r * n * cols + j) for j in range(n * cols)] for r in range(rows)]
    res = simulate(array_bench(d, rows, cols, ip, is_))
    tm = timings(d, d.experiment.t_window, rows)
    data = {"rows": rows, "cols": cols,
            "primary_signal_V": [[double_sampled(res, f"col_p_{c}", tm["primary"], r) for c in range(cols)]
                                 for r in range(rows)],
            "secondary_signal_V": [[double_sampled(res, f"col_s_{j}", tm["secondary"], r)
                                    for j in range(n * cols)] for r in range(rows)],
            "iph_primary_A": ip, "iph_secondary_A": is_}
    out = out or f"reports/{d.name}/array_{rows}x{cols}.png"
    data["plot"] = str(plot_columns(res, {"primary": [f"col_p_{c}" for c in range(cols)],
                                          "secondary": [f"col_s_{j}" for j in range(n * cols)]},
                                    Path(out), f"{d.name}: {rows} x {cols} readout (after SF, before AFE)"))
    emit(data, as_json, lambda x: "\n".join([f"plot: {x['plot']}"] + [
        f"row {r}: primary {[round(v * 1e3, 1) for v in x['primary_signal_V'][r]]} mV, "
        f"secondary {[round(v * 1e3, 1) for v in x['secondary_signal_V'][r]]} mV" for r in range(x["rows"])]))


@main.command()
@design_arg
@click.option("--out", type=click.Path(dir_okay=False), default=None,
              help="sized design file (default: DESIGN_sized.toml beside DESIGN)")
@click.option("--sensitivity", "with_sens", is_flag=True,
              help="also re-size at +-10 % C_j, +-20 % SF bias, each corner, +-10 K")
@json_opt
def size(design, out, with_sens, as_json):
    """Size the secondary mask opening and the integration times (5 % / mid-scale criterion)."""
    from .design import load_design
    from .optimize.flow import size_design
    from .report.text import size_text
    emit(size_design(load_design(design), out, with_sens), as_json, size_text)


@main.command()
@design_arg
@click.option("--out-dir", type=click.Path(file_okay=False), default="layouts", show_default=True)
@click.option("--rows", type=click.IntRange(1, 1000), default=2, show_default=True)
@click.option("--cols", type=click.IntRange(1, 1000), default=2, show_default=True)
@click.option("--golden", is_flag=True, help="(re)write layouts/golden/<design>.gds, the geometry baseline")
@json_opt
def layout(design, out_dir, rows, cols, golden, as_json):
    """Write the GDS (dual pixel + array), extract PD area/perimeter/photoactive area, draw 2D and 3D views."""
    from .design import load_design
    from .layout.cells import build_library
    from .layout.flow import layout_design, write_gds
    d = load_design(design)
    if golden:
        click.echo(f"wrote {write_gds(build_library(d, 2, 2), Path('layouts/golden') / f'{d.name}.gds')}")
        return
    r = layout_design(d, Path(out_dir), rows, cols)
    emit(r, as_json, lambda x: "\n".join([
        f"GDS: {x['gds']} (cells {', '.join(x['cells'])})", f"pictures: {x['png']}, {x['png_3d']}",
        *(f"  {w}: PD {x[w]['pd_area_m2'] * 1e12:.3f} um2, perimeter {x[w]['pd_perimeter_m'] * 1e6:.2f} um, "
          f"photoactive {x[w]['photoactive_area_m2'] * 1e12:.4f} um2" for w in ("primary", "secondary")),
        f"  C_A = {x['c_a']:.4f}"]))
