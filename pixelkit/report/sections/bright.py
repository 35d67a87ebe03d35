"""Bright sources: pixels 1 - 1000 full wells, with and without anti-blooming (``chip.bright``).

Independent path: the charge that reaches FD after its reset is set beside what the storage
node's own shielding lets in over the same time (I / gse), which is all that may reach it
with anti-blooming; the black-sun flag compares the over-exposed pixel with the same deck
at one full well.
"""
from __future__ import annotations

from . import Checked, Section, Table

TITLE = "Bright sources: over-exposure, black sun, blooming"


def build(ctx) -> Section:
    from ...chip.bright import BLACK_SUN, FACTORS, HOLDS, QUICK_FACTORS, figures
    factors, holds = (QUICK_FACTORS, (None,)) if ctx.quick else (FACTORS, HOLDS)
    ctx.progress("bright: over-exposed dual columns", 0, 1)
    rows = figures(ctx.design, factors, backend=ctx.backend, jobs=ctx.jobs, holds=holds)
    ctx.progress("bright: over-exposed dual columns", 1, 1)
    base = {(r["array"], r["anti_blooming"]): r.get("fd_after_reset_e") for r in rows if r["full_wells"] == 1.0}
    table, checked, failed = [], [], []
    for r in rows:
        ab = "on" if r["anti_blooming"] else "off"
        if "failed" in r:
            failed.append(f"{r['array']} {r['full_wells']:g} full wells, anti-blooming {ab}: {r['failed'][:200]}")
            table.append([r["array"], ab, r["full_wells"], r["current_A"] * 1e12] + ["failed"] * 7)
            continue
        extra = r["fd_after_reset_e"] - base[(r["array"], r["anti_blooming"])]
        table.append([r["array"], ab, r["full_wells"], r["current_A"] * 1e12, r["signal_V"] * 1e3,
                      r["of_full_well_signal"], "BLACK SUN" if r["black_sun"] else "clipped at the top",
                      extra, r["fd_light_e"], r["recovery_V"] * 1e3, r["recovery_afe_V"] * 1e3])
        tag = f"bright.{r['array']}.{'ab' if r['anti_blooming'] else 'no_ab'}.x{r['full_wells']:g}"
        checked.append(Checked(f"{tag}.of_full_well", r["of_full_well_signal"], "1", tol_abs=0.05))
        checked.append(Checked(f"{tag}.recovery_mV", r["recovery_V"] * 1e3, "mV", tol_abs=0.5))
    top = max(factors)
    first = {}
    for r in rows:
        if r.get("black_sun"):
            key = (r["array"], r["anti_blooming"])
            first[key] = min(first.get(key, r["full_wells"]), r["full_wells"])
    suns = [f"{k} (anti-blooming {'on' if ab else 'off'}) from {f:g} full wells" for (k, ab), f in sorted(first.items())]
    worst_rec = max((abs(r["recovery_V"]) for r in rows if "recovery_V" in r), default=float("nan"))
    text = [
        f"Each array's pixel driven to 1 - {top:g} full wells over its own integration time (primary "
        f"{ctx.design.primary.t_int * 1e3:g} ms, secondary {ctx.design.secondary.t_int * 1e3:g} ms), on a "
        "dual column of a frame with its AFE (rows dark, bright, dark), "
        + ("with the design's own anti-blooming setting (timing.ec_hold; the quick profile: the full one also "
           "runs the other)" if ctx.quick else "with EC holding the PD in reset while rows wait (anti-blooming, "
           "timing.ec_hold) and without")
        + ". The charge of the integration time is carried over the experiment window; after the exposure "
        "each pixel sees its real light.",
        f"Black sun (the bright pixel reads below {BLACK_SUN:.0%} of its full-well signal, because charge "
        "keeps reaching FD after its reset and pulls the reset level down): "
        + ("; ".join(suns) if suns else "none") + ". Charge onto FD after its reset, beyond the full-well "
        "pixel's: with anti-blooming only what the storage node's shielding lets in (I / gse, next column); "
        "without, the PD's overflow through TG.",
        f"Recovery of the column: the dark row after the bright one reads within {worst_rec * 1e3:.3f} mV "
        "of the dark row before it.",
        "docs/timing-and-settling.md describes the method; pixelkit sweep DESIGN --over iph_p=log:1p:3u:7 "
        "--over primary.timing.ec_hold=true,false reproduces the single-pixel curve."]
    if failed:
        text.append("Points that did not simulate: " + "; ".join(failed))
    tables = [Table("bright_source", "Bright source: over-exposed pixel, FD after reset, column recovery",
                    ["array", "anti-blooming", "full wells", "photocurrent (pA)", "signal (mV)",
                     "of full-well signal", "reads", "extra charge onto FD after reset (e-)",
                     "FD's own light over that time (e-)", "recovery, next dark row (mV)",
                     "recovery at the AFE (mV)"], table)]
    data = {"rows": rows}
    sto = _storage(ctx)
    if sto is not None:
        srows, note = sto
        tables.append(Table("bright_storage", "Storage node around a bright source during the readout (last row; "
                            "% of the column swing, clipped at 100)",
                            ["array", "light", "source (x background)", "GSE geometric", "geometric (%)",
                             "GSE modelled", "modelled (%)", "modelled FD charge (e-)",
                             "modelled, one pixel lit (%)", "modelled, its worst neighbour (%)",
                             "worst neighbour's FD charge (e-)"],
                            [[r["array"], r["light"], r["source_x_background"], r["geometric_gse"],
                              r["geometric_of_swing"] * 100, r.get("modelled_gse", "-"),
                              r["modelled_of_swing"] * 100 if "modelled_of_swing" in r else "-",
                              r.get("modelled_fd_e", "-"),
                              r["alone_of_swing"] * 100 if "alone_of_swing" in r else "-",
                              r["neighbour_of_swing"] * 100 if "neighbour_of_swing" in r else "-",
                              r.get("neighbour_fd_e", "-")] for r in srows]))
        text.append(note)
        data["storage"] = srows
    return Section(TITLE, text=text, checked=checked, tables=tables, data=data)


def _storage(ctx):
    """The storage-light table (``chip.bright.storage_table``), with the collection model where the report
    runs it (the light section's rule), or None without [optics] / [scene]."""
    d = ctx.design
    if d.optics is None or d.scene is None:
        return None
    from ...camera.spicenoise import sf_gain
    from ...chip.bright import storage_table
    exp = ctx.experiment()
    swing = {k: exp[k]["swing_V"] for k in ("primary", "secondary")}
    resp = hal = None
    if d.tech.collection is not None and (not ctx.quick or d.light.model == "modelled"):
        from ...layout.pex.collection import response
        from ...layout.pex.halo import halo
        resp = response(d)
        hal = halo(d)
    rows = storage_table(d, swing, sf_gain(d), resp, halo=hal)
    worst = {k: max(r["geometric_of_swing"] for r in rows if r["array"] == k and r["source_x_background"] == 1e3)
             for k in ("primary", "secondary")}
    note = (f"The storage node around a bright source: a source 1e3 - 1e5 x the background lit while the frame is "
            f"read (the last row waits {rows[0]['wait_s'] * 1e6:.3g} us primary) puts the photodiode's photocurrent "
            f"over the GSE on FD; FD's small capacitance turns it into up to {worst['primary'] * 100:.0f} % (primary) and "
            f"{worst['secondary'] * 100:.2g} % (secondary) of the swing at 1e3 x with geometric light. By light: the "
            "scene's halogen, a white LED, single wavelengths; modelled: each light's GSE and the secondary's "
            "effective opening from the collection model (docs/light-collection.md). The sign-off's "
            "storage_light_* figures measure the same in SPICE (docs/verify.md). Those are every pixel lit at the "
            "source's level; with the model, a source imaged on one dual pixel also: its own storage node with its "
            "neighbours dark, and the halo on its worst neighbour's (carriers diffusing from the lit pixel: Bloch "
            "solves of the pixel over a 3 x 3 supercell, layout.pex.halo).")
    return rows, note
