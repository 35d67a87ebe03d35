"""The 4T's dark-current figure against the dark deck's time step: why the post-layout view read 6.0 e-/s.

    python3 benchmarks/pixel4t_dark_steps.py [--json] [DESIGN.toml]

On ``DESIGN.toml`` (default ``designs/pixel4t_gf180.toml``), its schematic and its post-layout view
(``layout.pixel4t.post_layout_view``), in one run with a fresh ``PIXELKIT_CACHE``: the dark deck of
``rolepix/dark.py`` (a frame of the shortest exposure, one of the design's t_int; reltol 1e-7, vntol 1 nV)

1. at the design's dark currents, with the deck's largest step t_row/4 (the kit's), /16, /40, /100;
2. at the kit's step with the PPD's dark currents set to 0 and scaled by 100.

Printed per run: the dark signal (long frame's CDS output minus the short one's, uV), the short frame's
own CDS output (uV; ~0: no charge), the dark current it gives (e-/s, at the view's SPICE conversion gain),
and the CPU seconds of ngspice as a ratio to the kit's step in the same run. The scaled run is the
independent check: 100x the charge puts the signal far above the deck's time-step error, so its result
over 100 is the dark current the view's physics gives.
"""
from __future__ import annotations

import json
import sys
import time
from dataclasses import replace
from pathlib import Path

from common import ROOT, child_cpu_s, reference_design

DIVS = (4, 16, 40, 100)


def dark(design, div: int, scale: float = 1.0) -> dict:
    from pixelkit.circuits.cds import cds_bench, timing_of
    from pixelkit.measure.cds import cds
    from pixelkit.rolepix.dark import OPTIONS
    from pixelkit.rolepix.run import run
    from pixelkit.rolepix.signal import flush_exposure, signal
    from pixelkit.spice.netlist import Tran
    d = replace(design, ppd=replace(design.ppd, j_gen=design.ppd.j_gen * scale, j_dif=design.ppd.j_dif * scale))
    t0, t_int = flush_exposure(d), d.array.t_int
    ex = [t0, t0, max(t_int, 2 * t0)]
    tm = timing_of(d)
    net = cds_bench(d, d.cell(), ex, [[0.0, 0.0, 0.0]], title=f"p4t_dark_steps_{div}_{scale:g}")
    net = replace(net, options=(*net.options, *OPTIONS), analysis=Tran(1e-9, net.analysis.stop, 0.0, tm.t_row / div,
                                                                          uic=True))
    c0 = child_cpu_s()
    (r,) = run([net], d)
    cpu = child_cpu_s() - c0
    st = net.meta["frames"]["starts"]
    short, long_ = (cds(r, tm, ex, st, 0, f) for f in (1, 2))
    cg = signal(design)["cg_V_per_e"]
    return {"max_step_div": div, "dark_scale": scale, "dark_uV": (long_ - short) * 1e6, "short_uV": short * 1e6,
            "dark_e_per_s": (long_ - short) / cg / (ex[2] - ex[1]) / scale if scale else None,
            "cg_uV_per_e": cg * 1e6, "ngspice_cpu_s": cpu}


def main(argv) -> dict:
    as_json = "--json" in argv
    paths = [a for a in argv if not a.startswith("--")]
    path = Path(paths[0]) if paths else ROOT / "designs" / "pixel4t_gf180.toml"
    reference_design()   # the fresh cache
    from pixelkit.constants import Q
    from pixelkit.families.pixel4t.design import load_pixel4t_design
    from pixelkit.layout.pixel4t import post_layout_view
    from pixelkit.circuits.pixel4t import ppd_model
    from pixelkit.families.pixel4t.design import tg_channel
    d = load_pixel4t_design(path)
    p = ppd_model(d, tg_channel(d))
    out = {"design": str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else str(path),
           "derived_e_per_s": (p.i_gen + p.i_dif) / Q, "views": {}}
    t = time.time()
    for name, view in (("schematic", d), ("post-layout", post_layout_view(d))):
        runs = [dark(view, k) for k in DIVS] + [dark(view, 4, 0.0), dark(view, 4, 100.0)]
        base = runs[0]["ngspice_cpu_s"] or 1e-9
        for r in runs:
            r["cpu_ratio"] = r["ngspice_cpu_s"] / base
        out["views"][name] = runs
    out["wall_s"] = time.time() - t
    if as_json:
        print(json.dumps(out, indent=1))
    else:
        print(f"{out['design']}: derived dark current {out['derived_e_per_s']:.2f} e-/s")
        for name, runs in out["views"].items():
            for r in runs:
                print(f"{name:12s} step t_row/{r['max_step_div']:<4d} dark x{r['dark_scale']:<5g} "
                      f"signal {r['dark_uV']:9.3f} uV  short frame {r['short_uV']:7.3f} uV  "
                      f"{r['dark_e_per_s'] if r['dark_e_per_s'] is not None else float('nan'):8.2f} e-/s  cpu x{r['cpu_ratio']:.2f}")
    return out


if __name__ == "__main__":
    main(sys.argv[1:])
