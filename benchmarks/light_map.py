"""The modelled light map's collection model of the readout cells: its cost and result against the light field's
and the collection solver's code at a baseline revision, in the same run, on the same cells.

    python benchmarks/light_map.py [--baseline REV] [--grid UM] [--step NM] [--cells C,..]

For each readout cell of the GF180 design (``DUALPIX_COL``, ``AFE_P``, ``AFE_S``, as the light map draws them) at
the test suite's reduced collection model (1 um grid, 200 nm steps: ``tests/test_lightmap.py::REDUCED``) or the
given one: the collection maps (one 3D solve per junction, solved once and shared), then at every wavelength the
absorbed light by this revision's ``physics.lightfield.absorbed`` and by the baseline revision's (its file read
from git, loaded beside it), each timed (CPU), and the collected electrons per photon of every junction by both:
the ratio of the costs and the largest difference of the results, relative to the junction's own and to the
cell's largest collection. The baseline's code is the reference: the difference is what the change costs in
accuracy.
"""
from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import time

import numpy as np

from common import ROOT, reference_design


def baseline(rev: str, module: str):
    """``pixelkit.physics.<module>`` as it was at ``rev`` (a module beside the current one: its relative imports
    resolve in ``pixelkit.physics``)."""
    src = subprocess.run(["git", "-C", str(ROOT), "show", f"{rev}:pixelkit/physics/{module}.py"],
                         capture_output=True, text=True, check=True).stdout
    name = f"pixelkit.physics._{module}_baseline"
    spec = importlib.util.spec_from_loader(name, loader=None)
    mod = importlib.util.module_from_spec(spec)
    mod.__package__ = "pixelkit.physics"
    sys.modules[name] = mod
    exec(compile(src, f"{rev}:pixelkit/physics/{module}.py", "exec"), mod.__dict__)
    return mod


def cell(design, geo, name, grid, step, base, base_solve) -> dict:
    from pixelkit.layout.pex import collection as cl
    from pixelkit.layout.pex.light import _mapped
    from pixelkit.physics import collection as pc, lightfield as lf, silicon as si
    n = design.secondary_per_pixel
    own = {cl.polar(k, net) for k, nets in geo.junctions.items() if k in ("nsd", "psd") for net in nets
           if _mapped(name, net, n)}
    sil = cl.silicon(design, geo, grid, design.light.depth, own, (True, False))
    maps, t_maps = {}, {}
    for key, solve in (("base", base_solve), ("new", pc.solve)):
        c0 = time.process_time()
        maps[key] = solve(sil.grid, sil.labels, sil.n_type, sil.substrate)
        t_maps[key] = time.process_time() - c0
    wl = cl.wavelengths(design, step)
    n_ox = cl.require(design).dielectric_index
    t = {"new": 0.0, "base": 0.0}
    eta = {"new": [], "base": []}
    for w in wl:
        r = cl.ratio(grid, n_ox, w)
        o = cl.optics(design, geo, grid / r, None, "all", True, sil.grid.ny * r)
        args = (o, float(w), complex(si.index(w, design.temperature)), float(si.alpha(w, design.temperature)),
                sil.grid.z, r)
        for key, mod in (("base", base), ("new", lf)):
            c0 = time.process_time()
            ab = mod.absorbed(*args)
            t[key] += time.process_time() - c0
            col = maps[key].collected(ab.voxels, ab.deep)
            eta[key].append([col.get(k + 1, 0.0) for k in range(len(sil.nets))])
        print(f"  {name} {w * 1e9:.0f} nm: light grid {grid / r * 1e9:.0f} nm, {o.nx} x {o.ny} points", flush=True)
    new, old = np.array(eta["new"]), np.array(eta["base"])
    rel_own = float(np.max(np.abs(new - old) / np.maximum(np.abs(old), 1e-300)))
    rel_cell = float(np.max(np.abs(new - old)) / np.max(np.abs(old)))
    return {"maps_cpu_s": t_maps["new"], "baseline_maps_cpu_s": t_maps["base"], "light_cpu_s": t["new"], "baseline_light_cpu_s": t["base"],
            "max_rel_diff_own": rel_own, "max_rel_diff_cell": rel_cell, "nets": len(sil.nets), "wavelengths": wl.size}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--baseline", default="41facbb", help="the git revision whose light field is the baseline")
    ap.add_argument("--grid", type=float, default=1.0, help="lateral grid (um)")
    ap.add_argument("--step", type=float, default=200.0, help="wavelength step (nm)")
    ap.add_argument("--cells", default="DUALPIX_COL,AFE_P,AFE_S")
    a = ap.parse_args()
    d = reference_design(ROOT / "designs" / "dual_pixel_gf180.toml")
    from pixelkit.layout.pex import chip_geometry
    cells = a.cells.split(",")
    geos = chip_geometry(d, tuple(cells))
    base = baseline(a.baseline, "lightfield")
    base_solve = baseline(a.baseline, "collection").solve
    print(f"collection model of the readout cells at {a.grid:g} um, {a.step:g} nm; against {a.baseline}")
    tot = {"maps": 0.0, "base_maps": 0.0, "new": 0.0, "base": 0.0}
    for c in cells:
        r = cell(d, geos[c], c, a.grid * 1e-6, a.step * 1e-9, base, base_solve)
        tot["maps"] += r["maps_cpu_s"]
        tot["base_maps"] += r["baseline_maps_cpu_s"]
        tot["new"] += r["light_cpu_s"]
        tot["base"] += r["baseline_light_cpu_s"]
        print(f"{c}: maps {r['maps_cpu_s']:.1f} s CPU against {r['baseline_maps_cpu_s']:.1f} s ({r['nets']} junctions); "
              f"light field {r['light_cpu_s']:.1f} s CPU against {r['baseline_light_cpu_s']:.1f} s; collected electrons "
              f"per photon differ by at most {r['max_rel_diff_own']:.2g} of the junction's own, "
              f"{r['max_rel_diff_cell']:.2g} of the cell's largest", flush=True)
    new, old = tot["maps"] + tot["new"], tot["base_maps"] + tot["base"]
    print(f"total: maps {tot['maps']:.1f} s CPU against {tot['base_maps']:.1f} s (x {tot['maps'] / tot['base_maps']:.2f}), "
          f"light field {tot['new']:.1f} s against {tot['base']:.1f} s (x {tot['new'] / tot['base']:.2f}); the model "
          f"{new:.1f} s against {old:.1f} s at {a.baseline} (x {new / old:.2f})")


if __name__ == "__main__":
    main()
