"""Light collection: what the drawn pixel's junctions collect by wavelength (the collection model,
docs/light-collection.md), against the geometric light the kit otherwise uses: the masked
secondary's effective opening and where it comes from, each subpixel's GSE, and the sizing's C_M
under either light. Both are shown whatever ``light.model`` the design chose (it says which one the
rest of the report used). The full profile runs it for every design whose technology has a
``[collection]`` table; the quick profile only for a design that uses it (``light.model =
"modelled"``): the model takes about a minute the first time (cached after).
"""
from __future__ import annotations

import numpy as np

from . import Checked, Figure, Section, Table

TITLE = "Light collection: the masked secondary and the storage node by wavelength"


def _figure(ctx, by: dict, name: str):
    from ..figures import axes, save
    fig, (a, b) = axes(2, 10, 3.6)
    wl = np.asarray(by["wavelength_m"]) * 1e9
    a.semilogy(wl, np.asarray(by["effective_opening_m2"]) * 1e12, "C1", label="effective opening (modelled)")
    a.axhline(by["drawn_m2"] * 1e12, color="C1", ls="--", lw=1, label="drawn opening (geometric)")
    a.semilogy(wl, np.asarray(by["opening_transmission"]) * by["drawn_m2"] * 1e12, "C2", lw=1,
               label="drawn x the opening's transmission")
    a.set_xlabel("wavelength (nm)")
    a.set_ylabel("um2")
    a.set_title("the secondary: an opening lit like the primary")
    a.legend(fontsize=7)
    b.semilogy(wl, by["gse_primary"], "C0", label="primary (modelled)")
    b.semilogy(wl, by["gse_secondary"], "C1", label="secondary (modelled)")
    b.axhline(ctx.design.pixel.gse, color="k", ls="--", lw=1, label=f"pixel.gse = {ctx.design.pixel.gse:g} (geometric)")
    b.set_xlabel("wavelength (nm)")
    b.set_ylabel("GSE = eta_PD / eta_FD")
    b.set_title("storage node: charge GSE by wavelength")
    b.legend(fontsize=7)
    path = save(fig, ctx.figure(name))
    return Figure(path.name, "The collection model by wavelength: the secondary's effective opening (left) and "
                             "each subpixel's GSE (right), against the geometric light's constants")


def _sizings(ctx, d):
    """C_M under geometric and modelled light (SPICE-level curves); the modelled may be infeasible."""
    from ...errors import InfeasibleError
    from ...optimize.levels import spice_curves
    from ...optimize.sizing import Opening, opening_of, solve
    if d.optics is None or d.scene is None:
        return None, None, "no [optics] / [scene]: nothing to size"
    curves = spice_curves(d, ctx.experiment())
    geo = solve(d, curves, Opening())
    ctx.progress("light collection: the effective opening against the drawn one (sizing table)")
    try:
        return geo, solve(d, curves, opening_of(_modelled(d))), None
    except InfeasibleError as exc:
        return geo, None, str(exc)


def _modelled(d):
    from dataclasses import replace
    return replace(d, light=replace(d.light, model="modelled"))


def build(ctx) -> Section:
    d = ctx.design
    if d.tech.collection is None:
        return Section.unavailable(TITLE, f"technology {d.tech.name} has no [collection] table (the silicon's "
                                          "diffusion lengths, surface recombination, junction depths)")
    if d.scene is None:
        return Section.needs_input(TITLE, "a [scene] table", "the model weights its wavelengths by the scene's spectrum")
    if ctx.quick and d.light.model != "modelled":
        return Section(TITLE, text=["Quick profile: the collection model is not run here (about a minute the first "
                                    "time, cached after); the full profile shows it for every design, either profile "
                                    "for a design with light.model = \"modelled\" (docs/light-collection.md)."])
    from ...layout.pex.collection import response
    from ...layout.pex.lightfigures import decomposition, drawn, figures, scene_spectrum
    from ...physics.photo import Spectrum
    ctx.progress("light collection: the model of the drawn pixel")
    geo = drawn(d)
    resp = response(d, geo)
    spectra = {f"halogen ({d.scene.spectrum_temperature:g} K, the scene's)": scene_spectrum(d),
               "white LED (phosphor-converted)": Spectrum.white_led()}
    figs = {name: figures(d, resp, s) for name, s in spectra.items()}
    scene = figs[next(iter(spectra))]
    parts = decomposition(d)
    drawn = parts["drawn_m2"]
    geo_s, mod_s, why = _sizings(ctx, d)
    rows = [["secondary: effective opening (um2)", drawn * 1e12, *[f["effective_opening_m2"] * 1e12 for f in figs.values()]],
            ["secondary: effective / drawn", 1.0, *[f["effective_opening_m2"] / drawn for f in figs.values()]],
            ["GSE primary (eta_PD / eta_FD)", d.pixel.gse, *[f["gse_primary"] for f in figs.values()]],
            ["GSE secondary", d.pixel.gse, *[f["gse_secondary"] for f in figs.values()]]]
    both = Table("light_geometric_vs_modelled", f"Geometric light against the collection model (the design uses "
                 f"'{d.light.model}')", ["figure", "geometric", *[f"modelled, {n}" for n in spectra]], rows)
    parts_t = Table("light_effective_opening", f"Where the secondary's effective opening comes from ({next(iter(spectra))})",
                    ["part", "um2"],
                    [["drawn mask opening", drawn * 1e12],
                     ["drawn x the opening's transmission (diffraction, photon-weighted)", drawn * parts["transmission"] * 1e12],
                     ["collected from the light through its own opening", parts["own_m2"] * 1e12],
                     ["collected from the primary's light (the openings closed)", parts["primary_m2"] * 1e12],
                     ["all light together", parts["total_m2"] * 1e12]])
    by = dict(scene["by_wavelength"], drawn_m2=drawn)
    wl_t = Table("light_by_wavelength", "By wavelength (modelled)",
                 ["wavelength (nm)", "QE of the primary PD", "opening transmission", "effective opening (um2)",
                  "GSE primary", "GSE secondary"],
                 [[w * 1e9, q, t, a * 1e12, gp, gs] for w, q, t, a, gp, gs in
                  zip(by["wavelength_m"], by["qe_primary_pd"], by["opening_transmission"], by["effective_opening_m2"],
                      by["gse_primary"], by["gse_secondary"])])
    tables = [both, parts_t, wl_t]
    cm_rows = [["geometric", geo_s["c_m"] if geo_s else "-", geo_s["mask_open_m2"] * 1e12 if geo_s else "-",
                geo_s["mask_open_m2"] * 1e12 if geo_s else "-"]]
    cm_rows.append(["modelled", mod_s["c_m"], mod_s["mask_open_m2"] * 1e12, mod_s["effective_opening_m2"] * 1e12]
                   if mod_s else ["modelled", "no solution", "-", "-"])
    tables.append(Table("light_sizing", "The sizing's C_M under either light (SPICE-level curves)",
                        ["light", "C_M = A_pd / A_open", "drawn opening (um2)", "effective opening (um2)"], cm_rows))
    share = parts["primary_m2"] / parts["total_m2"]
    text = [f"The collection model of the drawn dual pixel (docs/light-collection.md): [Green2008] absorption, the "
            f"light field under the metals (the mask openings by the modal method), the carriers' diffusion to every "
            f"junction (3D, from the layout, depletion from the junction models), per wavelength "
            f"{by['wavelength_m'][0] * 1e9:.0f} - {by['wavelength_m'][-1] * 1e9:.0f} nm. The design uses "
            f"light.model = '{d.light.model}': the rest of this report's photocurrents and storage-node light are "
            f"{'the model' if d.light.model == 'modelled' else 'the geometric ones (mask opening, pixel.gse)'}.",
            f"Under the scene's light the secondary collects like an opening of {parts['total_m2'] * 1e12:.3g} um2 "
            f"({parts['total_m2'] / drawn:.3g} x its drawn {drawn * 1e12:.3g} um2): {share * 100:.0f} % of it is the "
            f"primary's light, carriers generated deep under the primary (near infrared is absorbed tens of microns "
            f"down) that diffuse to the secondary's photodiode, and light travelling under the shield; the opening "
            f"itself passes {parts['transmission']:.3g} of its drawn area's light. Under a white LED (no near "
            f"infrared) the effective opening is {figs['white LED (phosphor-converted)']['effective_opening_m2'] * 1e12:.3g} um2.",
            (f"The sizing's C_M: {geo_s['c_m']:.3g} with geometric light, "
             + (f"{mod_s['c_m']:.3g} with the model ({(mod_s['c_m'] / geo_s['c_m'] - 1) * 100:+.0f} %)." if mod_s
                else f"none with the model: {why}.")) if geo_s else f"No sizing: {why}."]
    checked = [Checked("light.effective_opening_m2", scene["effective_opening_m2"], "m2", tol_rel=0.03),
               Checked("light.gse_primary", scene["gse_primary"], "1", tol_rel=0.05),
               Checked("light.gse_secondary", scene["gse_secondary"], "1", tol_rel=0.05)]
    data = {"by_wavelength": {k: np.asarray(v).tolist() for k, v in by.items() if k != "drawn_m2"},
            "decomposition": parts, "spectra": {n: {k: v for k, v in f.items() if k != "by_wavelength"}
                                                for n, f in figs.items()},
            "sizing": {"geometric": geo_s, "modelled": mod_s, "why": why}}
    return Section(TITLE, text=text, tables=tables, figures=[_figure(ctx, by, "light_collection.png")],
                   checked=checked, data=data)
