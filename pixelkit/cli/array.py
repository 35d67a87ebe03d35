"""``pixelkit array``: one frame of the pixel arrays under a scene, up to the whole chip."""
from __future__ import annotations

import click

from .common import design_arg, emit, json_opt, load, main, out_opt, output_path, scheduler_address, spice_opts, post_layout_opt
from .types import FiniteRange
from ..chip.interp import LIMIT_V


@main.command("array")
@design_arg
@click.option("--rows", type=click.IntRange(1, 27), default=2, show_default=True)
@click.option("--cols", type=click.IntRange(1, 50), default=2, show_default=True,
              help="dual-pixel columns (the secondary array has N x as many)")
@click.option("--scene", default="gradient", show_default=True,
              help="gradient | uniform | a .csv / .npy map | an image (.png, .jpg, ...)")
@click.option("--unit", type=click.Choice(["lx", "W/m2", "A/m2", "rel", "fs"]), default=None,
              help="unit of the scene map (default: lx for .csv/.npy, rel for images, fs for the "
                   "built-in scenes); see pixelkit.chip.scene")
@click.option("--afe", "with_afe", is_flag=True, help="add each column's S1X/S2X samplers and SC AFE")
@click.option("--split", type=click.Choice(["columns", "rows", "none"]), default=None,
              help="columns: a chain of decks per group of columns, one per row, the column state handed "
                   "over (default with --afe); rows: one deck per array and row (default without; refused "
                   "with --afe); none: one deck per array (default with --seed). See pixelkit.chip.frame")
@click.option("--check", is_flag=True, help="also run the split and the undivided deck of each array at converged "
              "tolerances (reltol 1e-6) and report the largest difference; exit 1 above 0.1 mV or when void")
@click.option("--settling/--no-settling", default=True, show_default=True,
              help="also read every row with a long S1 and report each subpixel's settling error (twice the decks)")
@click.option("--settling-limit", type=FiniteRange(min=0, min_open=True), default=None,
              help="largest settling error (mV) the frame accepts, finite (default: the design's "
                   "[spec.settling_<array>] max, else 0.5 mV; --no-settling skips the measurement, and the "
                   "verdict then says it was not measured)")
@click.option("--interpolate/--exhaustive", default=True, show_default=True,
              help="with --afe, the column chains of an array whose columns each see one photocurrent in every row "
                   "(the default gradient) are interpolated in photocurrent from a few simulated ones and checked "
                   f"against held-out chains simulated too (all simulated when beyond {LIMIT_V * 1e3:g} mV); --exhaustive "
                   "simulates every chain. See pixelkit.chip.interp")
@click.option("--seed", type=click.IntRange(0, 2**31 - 1), default=None, help="Monte Carlo mismatch draw (GF180 statistical models)")
@click.option("--t-exp", "t_exp", type=FiniteRange(0.0, 10.0, min_open=True), default=None,
              help="simulated exposure in s (default: the experiment window); charge of t_int kept")
@click.option("--scheduler", default=None, callback=scheduler_address, help="Dask scheduler address (default: local workers)")
@out_opt("folder for frame.csv and frame.png (default reports/<design>/array_RxC)", folder=True)
@spice_opts
@post_layout_opt
@json_opt
def array_cmd(design, rows, cols, scene, unit, with_afe, split, check, settling, settling_limit, interpolate, seed, t_exp,
              scheduler, out, backend, jobs, as_json):
    """Simulate one frame of both arrays (with column circuits) under a scene."""
    from ..chip.frame import check_split, default_split, simulate_frame
    from ..chip.report import frame_table, plot_frame
    from ..chip.scene import default_map, load_map, photocurrents
    from ..fileio import write_atomic
    if check and seed is not None:
        raise click.UsageError("--check compares a split frame with the undivided deck; a Monte Carlo frame "
                               "(--seed) is simulated as one deck already")
    d = load(design, afe=with_afe)   # the post-layout view extracts the AFEs only for --afe
    m, default_unit = default_map(rows, d.secondary_per_pixel * cols, scene) if scene in ("gradient", "uniform") else load_map(scene)
    ph = photocurrents(d, rows, cols, m, unit or default_unit, t_exp)
    kw = dict(with_afe=with_afe, t_exp=t_exp, mismatch_seed=seed, backend=backend, jobs=jobs,
              scheduler=scheduler, compression=ph.compression)
    f = simulate_frame(d, ph.iph_p, ph.iph_s, split=split, settling=settling and seed is None, interpolate=interpolate,
                       **kw)
    from ..chip.settling import limits
    limit = limits(d, None if settling_limit is None else settling_limit * 1e-3)
    folder = output_path(out, d, f"array_{rows}x{cols}")
    from ..fileio import out_folder
    out_folder(folder)   # checked: a link, a file or a device there is refused (fileio)
    write_atomic(folder / "frame.csv", frame_table(f, ph))
    data = {**f.as_dict(), **ph.as_dict(), "csv": str(folder / "frame.csv"),
            "plot": str(plot_frame(f, folder / "frame.png", f"{d.name}: {rows} x {cols} frame", ph, limit))}
    data["settling"] = f.settling_summary(limit)
    data["verdict"] = verdict(data["settling"], ph.clipped, f.failures)
    if check:
        c = check_split(d, ph.iph_p, ph.iph_s, default_split(with_afe) if f.split == "none" else f.split, **kw)
        data["check"] = c
        diffs = [v for k, v in c.items() if k.startswith("max_diff") and v is not None]
        data["check_max_diff_V"] = max(diffs) if diffs else None
    if f.failures:
        data["error"] = "some decks failed"

    def text(x):
        same = (f" ({len(x['reused'])} column chain(s) identical to an earlier one's, not simulated: their values "
                f"are that chain's)") if x.get("reused") else ""
        lines = [f"{x['rows']} x {x['cols']} frame, {x['decks']} deck(s), {x['wall_s']:.1f} s{same}",
                 *interpolated_lines(x.get("interpolated", [])),
                 f"clipped (saturated): {x['clipped']}", *settling_lines(x["settling"]),
                 f"table: {x['csv']}", f"plot: {x['plot']}"]
        if "check" in x:
            c = x["check"]
            worst = "-" if x["check_max_diff_V"] is None else f"{x['check_max_diff_V'] * 1e3:.3f}"
            lines.append(f"{c['split']} split vs the undivided deck of each array, at reltol 1e-6 / abstol 1e-12: "
                         f"largest difference {worst} mV (signal, reset level"
                         f"{', AFE output' if 'max_diff_afe_V' in c else ''}; limit {c['limit_V'] * 1e3:g} mV): "
                         f"{'ok' if c['ok'] else 'FAILED'}")
            if c["void"]:
                lines.append(f"check void: decks failed or ran at looser options: {', '.join(c['void'][:5])}")
        lines += [f"FAILED {e['deck']}: {e['message']}" for e in x["failures"]]
        lines += [f"retried with looser options {e['deck']}: {e['message']}" for e in x["retried"]]
        lines.append(f"frame: {x['verdict']['text']}")
        return "\n".join(lines)
    emit(data, as_json, text)
    if f.failures:
        raise SystemExit(4)
    if check and not (data["check"]["ok"] and data["verdict"]["ok"]):
        raise SystemExit(1)


def interpolated_lines(recs) -> list[str]:
    """What ``chip.interp`` did per array: interpolated and checked, or simulated whole after all."""
    out = []
    for r in recs:
        diff = "-" if r["max_diff_V"] is None else f"{r['max_diff_V'] * 1e3:.4f} mV"
        check = (f"held-out chains {', '.join(r['held_out_chains'])} simulated too: largest difference {diff} "
                 f"(limit {r['limit_V'] * 1e3:g} mV)")
        if r["used"]:
            at = (f"{r['currents']} currents spread over their places" if r.get("places_shared")
                  else f"{r['currents']} currents per place")
            out.append(f"{r['array']}: {r['chains']} column chain(s) interpolated in photocurrent from {r['anchors']} "
                       f"simulated anchor chains ({at}); {check}")
        else:
            out.append(f"{r['array']}: every column chain simulated ({r['why']}; {check})")
    return out


def settling_lines(s) -> list[str]:
    from ..chip.settling import describe
    if s is None:
        return ["settling: not measured (--no-settling, or a Monte Carlo frame)"]
    worst = ", ".join(f"{k} {'-' if v is None else f'{v * 1e3:.3f}'} mV" for k, v in s["worst_V"].items())
    lim = ", ".join(f"{k} {v * 1e3:g} mV" for k, v in s["limit_V"].items())
    lines = [f"settling (each row against the same read with long S1 and S2): worst {worst} (limit {lim})"]
    return lines + [f"  beyond the limit: {ln}" for ln in describe(s)] + [f"  {n}" for n in s["notes"][:5]]


def verdict(s, clipped: dict, failures) -> dict:
    """``ok`` only when no deck failed, no subpixel is clipped and every measured settling
    error is within its limit; ``text`` says which of these is not so."""
    why = []
    if failures:
        why.append(f"{len(failures)} deck(s) failed")
    if any(clipped.values()):
        why.append("clipped subpixels: " + ", ".join(f"{k} {n}" for k, n in clipped.items() if n))
    if s is None:
        why.append("settling not measured")
    else:
        beyond = {k: len(v) for k, v in s["beyond"].items() if v}
        if beyond:
            why.append("settling beyond its limit: " + ", ".join(f"{k} {n}" for k, n in beyond.items()))
        if s["not_measured"]:
            why.append(f"settling of {s['not_measured']} subpixel(s) not measured")
    return {"ok": not why, "text": "ok" if not why else "NOT ok: " + "; ".join(why)}
