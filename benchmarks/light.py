"""The light-collection model on the reference dual pixel: its cost from an empty cache against one
SPICE run of the pixel (same process), the cache's, and the figures docs/light-collection.md quotes.

    python benchmarks/light.py [--design D.toml] [--convergence] [--sensitivity]

- cost: drawing and extracting the dual pixel, the collection maps (one 3D solve per photodiode and
  storage node, the rest of the junctions together), the light field and collection at every
  wavelength; then the same again from the cache. Wall and CPU seconds, and the ratio to one SPICE run.
- figures: the secondary's effective opening and each subpixel's GSE under the scene's halogen light
  and a white LED, the decomposition of the effective opening, the mask opening's transmission;
  the GSE against the published figures of metal-shielded floating-diffusion global-shutter pixels.
- ``--convergence``: the same at a finer lateral grid (0.2 um) and a wavelength step of 12.5 nm: how far
  the default grid's figures are from converged.
- ``--sensitivity``: the effective opening and GSE with the substrate's electron diffusion length at
  30 and 10 um, and over a p- epitaxial layer 10 um thick on a p+ substrate (recombining bottom).
"""
from __future__ import annotations

import argparse
import dataclasses
import time

from common import ROOT, child_cpu_s, reference_design

#: the GSE of metal-shielded floating-diffusion global-shutter pixels in production, as [Thesis2019]
#: quotes Aptina's four generations (6 / 3.75 / 3.7 / 2.8 um pitch): 1700, 310, 3000, 2200
PUBLISHED_GSE = (310.0, 3000.0)


def _clock():
    return time.perf_counter(), time.process_time() + child_cpu_s()


def _since(t):
    """(wall, CPU) seconds since ``t``: this process's CPU and its children's (ngspice)."""
    return time.perf_counter() - t[0], time.process_time() + child_cpu_s() - t[1]


def figures(d, say=print) -> dict:
    from pixelkit.layout.pex.collection import pixel_geometry, response
    from pixelkit.layout.pex.lightfigures import decomposition, figures as figs, scene_spectrum
    from pixelkit.physics.photo import Spectrum
    r = response(d, pixel_geometry(d))
    out = {"halogen": figs(d, r, scene_spectrum(d)), "LED": figs(d, r, Spectrum.white_led())}
    out["parts"] = decomposition(d)
    out["response"] = r
    return out


def show(d, f, title):
    h, led, p = f["halogen"], f["LED"], f["parts"]
    print(f"{title}:")
    print(f"  secondary effective opening: halogen {h['effective_opening_m2'] * 1e12:.3g} um2, white LED "
          f"{led['effective_opening_m2'] * 1e12:.3g} um2 (drawn {p['drawn_m2'] * 1e12:.3g} um2)")
    print(f"    own opening's light {p['own_m2'] * 1e12:.3g} um2, the primary's light {p['primary_m2'] * 1e12:.3g} um2, "
          f"the opening's transmission {p['transmission']:.3f}")
    print(f"  GSE primary: halogen {h['gse_primary']:.0f}, LED {led['gse_primary']:.0f}; secondary: halogen "
          f"{h['gse_secondary']:.0f}, LED {led['gse_secondary']:.0f} (pixel.gse = {d.pixel.gse:g})")
    lo, hi = PUBLISHED_GSE
    ok = lo <= h["gse_primary"] <= hi
    print(f"  published FD-storage GS pixels (Aptina, [Thesis2019]): {lo:g} - {hi:g}; the primary's "
          f"{'is within' if ok else 'is OUTSIDE'} it")
    by = h["by_wavelength"]
    print("  nm    QE_PD  T_open  A_eff(um2)  GSE_p   GSE_s")
    for i in range(0, len(by["wavelength_m"]), 4):
        print(f"  {by['wavelength_m'][i] * 1e9:4.0f}  {by['qe_primary_pd'][i]:.3f}  {by['opening_transmission'][i]:.3f}"
              f"  {by['effective_opening_m2'][i] * 1e12:9.3g}  {by['gse_primary'][i]:6.0f}  {by['gse_secondary'][i]:6.0f}")


def show_halo(d, resp, hal):
    """The halo's figures: GSE-like ratios of one lit pixel's own storage node and its neighbours', and the shares
    of the uniform scene's storage-node charge by offset and wavelength."""
    from pixelkit.layout.pex.halo import figures as halo_figures
    from pixelkit.layout.pex.lightfigures import scene_spectrum
    from pixelkit.physics.photo import Spectrum
    for name, spec in (("halogen", scene_spectrum(d)), ("white LED", Spectrum.white_led())):
        for kind, f in halo_figures(d, resp, hal, spec).items():
            print(f"  halo, {name}, {kind}: GSE one pixel lit {f['gse_alone']:.0f}, worst neighbour {f['neighbour']} "
                  f"{f['gse_neighbour']:.0f}, eight neighbours together {f['gse_all_neighbours']:.0f}")
    print("  share of the uniform scene's storage-node charge, by the lit pixel's offset (p.fd / s0.fd)")
    print("  nm    own          left         right        below        above")
    for i in range(0, len(hal.wavelength_m), 4):
        cols = []
        for dd in ("0,0", "-1,0", "1,0", "0,-1", "0,1"):
            cols.append("/".join(f"{hal.eta[dd][n][i] / hal.periodic[n][i]:.3f}" for n in ("p.fd", "s0.fd")))
        print(f"  {hal.wavelength_m[i] * 1e9:4.0f}  " + "  ".join(cols))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--design", default=str(ROOT / "designs" / "dual_pixel_revA.toml"))
    ap.add_argument("--convergence", action="store_true")
    ap.add_argument("--sensitivity", action="store_true")
    a = ap.parse_args()
    d = reference_design(a.design)
    from pixelkit.circuits.testbench import dual_pixel_bench
    from pixelkit.layout.pex import collection as cl
    from pixelkit.spice import simulate
    t = _clock()
    simulate(dual_pixel_bench(d, 1e-9, 4e-11), use_cache=False)
    spice = _since(t)
    print(f"one SPICE run of the dual-pixel bench (baseline): {spice[0]:.2f} s wall, {spice[1]:.2f} s CPU")
    t = _clock()
    geo = cl.pixel_geometry(d)
    g = _since(t)
    sil = cl.silicon(d, geo, d.light.grid, d.light.depth)
    t = _clock()
    cl.maps(sil)
    m = _since(t)
    t = _clock()
    cl.response(d, geo)
    r = _since(t)
    t = _clock()
    cl.response(d, cl.pixel_geometry(d))
    c = _since(t)
    from pixelkit.layout.pex import halo as hm
    t = _clock()
    hal = hm.halo(d, geo)
    hc = _since(t)
    t = _clock()
    hm.halo(d, geo)
    hcc = _since(t)
    total = (g[0] + m[0] + r[0], g[1] + m[1] + r[1])
    n = len(cl.wavelengths(d))
    print(f"grid {sil.grid.nx} x {sil.grid.ny} x {sil.grid.nz} ({sil.grid.nx * sil.grid.ny * sil.grid.nz} voxels), "
          f"{len(sil.nets)} collection maps, {n} wavelengths")
    for label, (w, cpu) in (("draw + extract the dual pixel", g), ("collection maps (cold)", m),
                            (f"light field + collection, {n} wavelengths (cold)", r),
                            ("the model, empty cache (sum)", total), ("the model again, from the cache", c),
                            (f"the halo, {hal.cells[0]} x {hal.cells[1]} Bloch solves (cold)", hc),
                            ("the model and its neighbours' halo (sum)", (total[0] + hc[0], total[1] + hc[1])),
                            ("the halo again, from the cache", hcc)):
        print(f"  {label:<52} {w:7.1f} s wall {cpu:7.1f} s CPU  {w / spice[0]:7.1f} x baseline")
    f = figures(d)
    show(d, f, "figures (default grid)")
    show_halo(d, f["response"], hal)
    if a.convergence:
        fine = dataclasses.replace(d, light=dataclasses.replace(d.light, grid=0.2e-6, wavelength_step=12.5e-9))
        show(fine, figures(fine), "the same at a 0.2 um grid, 12.5 nm steps")
    if a.sensitivity:
        c0 = d.tech.collection
        for label, col in (("electron diffusion length 30 um", dataclasses.replace(c0, electron_diffusion_length=30e-6)),
                           ("electron diffusion length 10 um", dataclasses.replace(c0, electron_diffusion_length=10e-6)),
                           ("10 um p- epitaxial layer on p+ (recombining bottom)",
                            dataclasses.replace(c0, substrate_thickness=10e-6, substrate_bottom="recombining"))):
            v = dataclasses.replace(d, tech=dataclasses.replace(d.tech, collection=col))
            show(v, figures(v), label)


if __name__ == "__main__":
    main()
