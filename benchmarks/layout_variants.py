"""Robustness of the generators: design variants (device sizes, PD sizes, mask openings) drawn,
each through the kit's LVS, and all of them in one run of the foundry's DRC deck (deep mode:
each variant's cells are reported under their own names).

Prints per variant: drawn or the layout error it gets, LVS, DRC violations; and the totals.

    python3 benchmarks/layout_variants.py
"""
from __future__ import annotations

import tempfile
import time
from dataclasses import replace
from pathlib import Path

import gdstk
from common import ROOT

from pixelkit.design import load_design
from pixelkit.layout.flow import write_gds
from pixelkit.layout.library import build_cells, to_library
from pixelkit.layout.rules import RuleError
from pixelkit.layout.signoff.drc import run_drc
from pixelkit.layout.signoff.lvs import run_lvs

UM = 1e-6


def variants(d):
    dev = d.pixel.devices

    def devs(**kw):
        return replace(d, pixel=replace(d.pixel, devices=replace(dev, **kw)))

    def sec(**kw):
        return replace(d, secondary=replace(d.secondary, **kw))
    yield "ref", d
    yield "sf_w_0.6", devs(sf_w=0.6 * UM)
    yield "sf_w_1.4", devs(sf_w=1.4 * UM)
    yield "l_0.35", devs(ec_l=0.35 * UM, tg_l=0.35 * UM, rst_l=0.35 * UM, sf_l=0.35 * UM, rs_l=0.35 * UM)
    yield "l_0.8", devs(ec_l=0.8 * UM, tg_l=0.8 * UM, rst_l=0.8 * UM)
    yield "w_0.3", devs(ec_w=0.3 * UM, tg_w=0.3 * UM, rst_w=0.3 * UM, rs_w=0.3 * UM)
    yield "sw_2_load_4", devs(sw_w=2 * UM, load_l=4 * UM)
    yield "opening_0.4", sec(mask_opening=0.4e-12)
    yield "opening_1.5", sec(mask_opening=1.5e-12)
    yield "pd_5x5.3", sec(pd_height=5.3 * UM)
    yield "pd_primary_14", replace(d, primary=replace(d.primary, pd_width=14 * UM, pd_height=12 * UM))


def main() -> None:
    out = Path(tempfile.mkdtemp(prefix="pk-variants-"))
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    top = gdstk.Cell("TOP")
    x = 0.0
    rows = []
    t0 = time.perf_counter()
    designs = {}
    for f in ("dual_pixel_revA.toml", "dual_pixel_gf180.toml"):
        d = load_design(ROOT / "designs" / f)
        for name, v in variants(d):
            key = f"{d.tech.name[:3]}_{name}"
            try:
                cells = build_cells(v)
            except RuleError as exc:
                rows.append((key, f"layout error: {exc.rule} ({exc.field or exc.place})", "-"))
                continue
            gds = write_gds(to_library(v, cells, 2, 2), out / f"{key}.gds")
            lvs = run_lvs(gds, "DUALPIX_COL", v)
            sub = to_library(v, cells, 2, 2)
            for c in sub.cells:
                c.name = f"{key}__{c.name}"
                lib.add(c)
            for name in ("DUALPIX_COL", "ARRAY_2X2"):
                cell = next(c for c in sub.cells if c.name == f"{key}__{name}")
                top.add(gdstk.Reference(cell, (x, 0)))
                (x0, _), (x1, _) = cell.bounding_box()
                x += (x1 - x0) + 20
            designs[key] = v
            rows.append((key, "drawn", "match" if lvs.match else f"MISMATCH {lvs.mismatches[:2]}"))
    gen = time.perf_counter() - t0
    lib.add(top)
    path = out / "all.gds"
    lib.write_gds(str(path))
    any_design = next(iter(designs.values()))
    drc = run_drc(path, "TOP", any_design.tech, out / "drc")
    print(f"{len(rows)} variants, generation + LVS {gen:.1f} s, one DRC run {drc.seconds:.1f} s ({drc.klayout})")
    for key, state, lvs in rows:
        bad = {v.rule: v.count for v in drc.violations if v.cell.startswith(f"{key}__")}
        print(f"  {key:24s} {state:40s} LVS {lvs:10s} DRC {bad or 'clean' if state == 'drawn' else '-'}")
    other = [v for v in drc.violations if "__" not in v.cell]
    if other:
        print("  violations between cells (TOP):", {v.rule: v.count for v in other})


if __name__ == "__main__":
    main()
