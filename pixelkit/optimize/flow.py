"""The ``pixelkit size`` flow: both levels, SPICE verification, sized design file, sensitivity."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from ..circuits.testbench import dual_pixel_bench, timings
from ..experiments.thesis import run_experiment
from ..errors import InfeasibleError, PixelkitError
from ..fileio import check_output, moved_path, path_kind, write_atomic
from ..measure.pixel import double_sampled
from ..schema import to_toml
from ..spice import simulate
from .levels import analytic_curves, spice_curves
from .sizing import Opening, light, opening_of, solve

WHY = ("The analytic level sees only the PD node (PD junction + EC/TG diffusions) and takes the "
       "signal as its voltage drop over the design swing; the SPICE level reads the double-sampled "
       "column signal, where FD charge sharing, the SF gain and the measured column swing make the "
       "secondary's 5 % point cost relatively less charge than the primary's mid-scale point, so "
       "it needs a larger opening (smaller C_M).")


def verify(design, sized: dict, experiment: dict) -> dict:
    """Simulate the sized design at the background light over its real integration times.

    Each array is exposed for its own sized time (1 ms-scale primary, 12 ms-scale
    secondary, transfers aligned) at the photocurrent the background gives its
    photoactive area: a run independent of the short-window experiment the sizing
    was solved from. The fraction is (signal - experiment's pedestal) / swing.
    """
    lt = light(design)
    i_p = lt.j_bg * design.primary.area
    i_s = lt.j_bg * sized.get("effective_opening_m2", sized["mask_open_m2"])
    tm = timings(design, sized["t_int_primary_s"], 1, sized["t_int_secondary_s"])
    r = simulate(dual_pixel_bench(design, i_p, i_s, title="size_verify", tm=tm))
    fp = (double_sampled(r, "col_p", tm["primary"]) - experiment["primary"]["pedestal_V"]) \
        / experiment["primary"]["swing_V"]
    fs = (double_sampled(r, "col_s0", tm["secondary"]) - experiment["secondary"]["pedestal_V"]) \
        / experiment["secondary"]["swing_V"]
    return {"primary_frac": fp, "secondary_frac": fs, "i_primary_A": i_p, "i_secondary_A": i_s,
            "t_int_primary_s": sized["t_int_primary_s"], "t_int_secondary_s": sized["t_int_secondary_s"],
            "retried": [dict(r.meta["retried"], deck=r.meta["title"])] if r.meta.get("retried") else []}


def sized_name(name: str) -> str:
    """``<name>_sized``, kept a valid design name (at most 64 characters, no double suffix)."""
    base = name[: -len("_sized")] if name.endswith("_sized") else name
    return base[: 64 - len("_sized")] + "_sized"


def sized_design_text(design, sized: dict, out: Path | None = None) -> str:
    """The design file with the sized values; loads again from ``out`` (strings escaped by
    ``to_toml``, a valid name, relative technology / layout paths rewritten for ``out``'s folder)."""
    from ..tech import builtin_names
    raw = {k: (dict(v) if isinstance(v, dict) else v) for k, v in design.raw.items()}
    raw["name"] = sized_name(design.name)
    raw["secondary"]["mask_opening"] = f"{sized['mask_open_m2'] * 1e12:.4f} um2"
    raw["primary"]["t_int"] = f"{sized['t_int_primary_s'] * 1e6:.2f} us"
    raw["secondary"]["t_int"] = f"{sized['t_int_secondary_s'] * 1e6:.2f} us"
    if out is not None:
        old_dir, new_dir = Path(design.source).parent, Path(out).parent
        if raw["technology"] not in builtin_names():
            raw["technology"] = moved_path(raw["technology"], old_dir, new_dir)
        if isinstance(raw.get("layout"), dict) and "gds" in raw["layout"]:
            raw["layout"]["gds"] = moved_path(raw["layout"]["gds"], old_dir, new_dir)
    source = "".join(c if c.isprintable() else "?" for c in str(design.source))
    head = (f"# Sized by pixelkit size from {source} ({sized['level']} level):\n"
            f"# C_M = {sized['c_m']:.2f}, opening {sized['mask_open_m2'] * 1e12:.4f} um2\n")
    return head + to_toml(raw)


def variants(design):
    """(label, design) pairs of the sensitivity table."""
    pd = design.tech.photodiode
    out = []
    for k in (0.9, 1.1):
        tech = replace(design.tech, photodiode=replace(pd, cj=pd.cj * k, cjsw=pd.cjsw * k))
        out.append((f"C_j x{k:g}", replace(design, tech=tech)))
    for k in (0.8, 1.2):
        out.append((f"SF bias x{k:g}", replace(design, pixel=replace(design.pixel, sf_bias=design.pixel.sf_bias * k))))
    for c in sorted(design.tech.models.corners):
        out.append((f"corner {c}", replace(design, corner=c)))
    for dt in (-10.0, 10.0):
        sc = replace(design.scene, max_temperature=design.scene.max_temperature + dt)
        out.append((f"temperature {dt:+g} K", replace(design, temperature=design.temperature + dt, scene=sc)))
    return out


def sensitivity(design, nominal: dict, backend="batch", opening: Opening | None = None) -> list[dict]:
    """Re-sized per variant; the secondary's opening law (geometric, or the collection model's) held at
    the nominal design's (``opening``)."""
    from ..progress import progress
    rows = []
    opening = opening if opening is not None else opening_of(design)
    for label, d in progress(list(variants(design)), desc="sensitivity (re-sizing each variant)", unit="variant"):
        s = solve(d, spice_curves(d, run_experiment(d, backend=backend)), opening)
        rows.append({"variant": label, "c_m": s["c_m"], "mask_open_m2": s["mask_open_m2"],
                     "t_int_primary_s": s["t_int_primary_s"], "t_int_secondary_s": s["t_int_secondary_s"],
                     "c_m_change_frac": s["c_m"] / nominal["c_m"] - 1,
                     "t_primary_change_frac": s["t_int_primary_s"] / nominal["t_int_primary_s"] - 1})
    return rows


def size_result(design, out: Path | None = None, with_sensitivity: bool = False,
                backend="batch") -> tuple[dict, str]:
    """Everything ``pixelkit size`` computes (both levels, the SPICE verification, the sensitivity
    table) and the sized design file's text, nothing written: the file is written last, so a run
    interrupted before the end leaves no file and a run that wrote it has finished."""
    out = Path(out) if out else Path(design.source).with_name(f"{Path(design.source).stem}_sized.toml")
    check_output(out)  # before the simulations, not after them
    if path_kind(out) == "dir":
        raise PixelkitError(f"{out}: cannot write the sized design here: it is a folder (give a file name)")
    exp = run_experiment(design, backend=backend)
    opening = opening_of(design)
    curves = {"analytic": analytic_curves(design), "spice": spice_curves(design, exp)}
    geometric = solve(design, curves[design.sizing.level], Opening()) if not opening.geometric else None
    try:
        analytic = solve(design, curves["analytic"], opening)
        spice = solve(design, curves["spice"], opening)
    except InfeasibleError as exc:
        if geometric is not None:     # say what the geometric light would have sized
            raise InfeasibleError(f"{str(exc).split(': constraints in conflict')[0]}; with geometric light C_M = {geometric['c_m']:.3g} "
                                  f"({geometric['mask_open_m2'] * 1e12:.3g} um2)", exc.conflicts) from None
        raise
    chosen = spice if design.sizing.level == "spice" else analytic
    result = {k: chosen[k] for k in ("c_m", "mask_open_m2", "effective_opening_m2", "light",
                                     "t_int_primary_s", "t_int_secondary_s",
                                     "trace_px_at_speed_min", "motion_px_primary", "dark_frac_secondary",
                                     "headlight_frac")}
    checked = verify(design, chosen, exp)
    result.update(level=chosen["level"], solve_time_s=analytic["solve_time_s"],
                  verify=checked, levels={"analytic": analytic, "spice": spice},
                  why_levels_differ=WHY, sized_design=str(out),
                  retried=exp.get("retried", []) + checked.pop("retried"))
    if geometric is not None:
        result["geometric"] = {k: geometric[k] for k in ("c_m", "mask_open_m2", "t_int_primary_s", "t_int_secondary_s")}
        result["c_m_change_frac"] = chosen["c_m"] / geometric["c_m"] - 1
    if with_sensitivity:
        result["sensitivity"] = sensitivity(design, spice, backend, opening)
    return result, sized_design_text(design, chosen, out)


def size_design(design, out: Path | None = None, with_sensitivity: bool = False, backend="batch") -> dict:
    """``size_result``, then the sized design file written (atomically) where it says."""
    result, text = size_result(design, out, with_sensitivity, backend)
    write_atomic(result["sized_design"], text)
    return result
