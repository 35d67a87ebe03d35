"""Layout sign-off: the 2 x 2 array with its AFE columns and the full light shield, through the
foundry's DRC deck and the kit's LVS; the area of every block and of the design's whole chip;
the junction the shield leaves open.

Independent paths: the DRC verdict is the foundry deck's (GlobalFoundries' GF180MCU deck run by
KLayout), not the generator's; LVS compares the extracted layout with the netlist the
simulations use; the open junction is measured on the GDS read back and set beside the
openings the design file asks for (its PD and mask-opening sizes). Quick profile: LVS and the
shield only (the full profile runs the deck; so does `pixelkit layout --afe --drc`). The deck's
result is kept in the DRC cache (``signoff/drc.py``): a report rebuilt on the same drawing (a code
change elsewhere, ``--no-cache``) reads the deck's report back instead of running it again.
"""
from __future__ import annotations

from ...errors import PixelkitError
from . import Checked, Figure, Section, Table

TITLE = "Layout sign-off"
ROWS = COLS = 2
PICTURES = 6          # violation pictures at most (one per rule)


def build(ctx) -> Section:
    from ...layout.flow import layout_design
    d = ctx.design
    if d.tech.passives is None:
        return Section.unavailable(TITLE, f"technology {d.tech.name} names no MIM capacitor / resistor "
                                          "([passives]): the AFE cannot be drawn")
    run_drc = not ctx.quick and bool(d.tech.signoff.drc_deck)
    chip_checks = run_drc and bool(d.tech.signoff.pv_decks)     # the foundry's LVS, density, antenna (fd_pv)
    folder = ctx.figure("layout_signoff/x").parent
    ctx.progress("layout sign-off: 2 x 2 array with its AFEs" + (", fill, foundry DRC / LVS / density / antenna"
                                                                if chip_checks else ", foundry DRC" if run_drc else "")
                 + ", LVS")
    try:
        r = layout_design(d, folder, ROWS, COLS, pictures=False, drc=run_drc, lvs=True, afe=True, shield="full",
                          foundry_lvs=chip_checks, density=chip_checks, antenna=chip_checks, fill=chip_checks,
                          drc_cache=True)
    except PixelkitError as exc:
        return Section.unavailable(TITLE, f"the layout cannot be signed off: {exc}")
    from ...layout.render import plot_exposure
    text, tables, figures, checked, files = [], [], [], [], []

    def rel(p) -> str:
        return "layout_signoff/" + str(p).rsplit("/", 1)[-1]
    files.append(rel(r["gds"]))
    # DRC -------------------------------------------------------------------------------------
    drc = r.get("drc")
    if drc is None:
        text.append("DRC: not run in the quick profile (the full profile runs the foundry deck, as "
                    f"`pixelkit layout {d.name}.toml --afe --drc` does).")
        drc_rows = [["(not run: quick profile)", "", "", "", ""]]
    else:
        text.append(f"DRC: {drc['deck'].rsplit('/', 1)[-1]} ({drc['klayout']}, {drc['options'].get('run_mode', '')} "
                    f"mode, {_rules_run(drc['report'])} rules in its report) on {r['top']}: "
                    + ("no violation." if drc["clean"] else f"{drc['total']} violation(s) in {len(drc['by_rule'])} rule(s)."))
        drc_rows = []
        for k, v in enumerate(drc["violations"]):
            pic = ""
            if k < PICTURES:
                from ...layout.render import plot_violation
                p = plot_violation(r["gds"], v["cell"], v["where"], d.tech, ctx.figure(f"layout_signoff/drc_{k}.png"),
                                   f"{v['rule']} in {v['cell']}")
                pic = rel(p)
                figures.append(Figure(pic, f"{v['rule']}: {v['description']} (first at {v['where']})"))
            drc_rows.append([v["rule"], v["count"], v["cell"], v["where"], pic])
        if not drc_rows:
            drc_rows = [["(none)", 0, "", "", ""]]
        checked.append(Checked("layout_signoff.drc_violations", drc["total"], "1",
                               note=f"{d.tech.signoff.drc_deck} deck {drc['deck'].rsplit('/', 1)[-1]}"))
        files.append(rel(drc["report"]))
    tables.append(Table("layout_signoff_drc", "DRC: violations per rule (count, the first location, its picture)",
                        ["rule", "count", "cell", "first location (cell coordinates, um)", "picture"], drc_rows))
    # LVS -------------------------------------------------------------------------------------
    lvs = r["lvs"]
    text.append(f"LVS (the kit's extraction against the simulations' netlists) on {r['top']}: "
                + ("match." if lvs["match"] else f"{len(lvs['mismatches'])} mismatch(es): "
                   + "; ".join(lvs["mismatches"][:5])))
    tables.append(Table("layout_signoff_lvs", "LVS", ["cell", "result", "mismatches"],
                        [[r["top"], "match" if lvs["match"] else "mismatch", "; ".join(lvs["mismatches"][:20])]]))
    checked.append(Checked("layout_signoff.lvs_match", float(lvs["match"]), "1"))
    text.append(_foundry_text(r, run_drc, d))
    # areas -----------------------------------------------------------------------------------
    area_rows = _areas(d, r)
    tables.append(Table("layout_signoff_areas", "Area per block",
                        ["block", "cells", "width (um)", "height (um)", "area (um2)"], area_rows))
    # the shield ------------------------------------------------------------------------------
    sh = r["shield"]
    sh_rows = [[k, v["junction_m2"] * 1e12, v["exposed_m2"] * 1e12] for k, v in sh["blocks"].items()]
    sh_rows.append(["all", sum(v["junction_m2"] for v in sh["blocks"].values()) * 1e12, sh["exposed_m2"] * 1e12])
    tables.append(Table("layout_signoff_shield", f"Junction (COMP or n-well) left open by every metal, per block "
                        f"(--shield full, {ROWS} x {COLS} array; openings the design asks: "
                        f"{sh['openings_m2'] * 1e12:.4g} um2)", ["block", "junction (um2)", "left open (um2)"], sh_rows))
    text.append(f"The light shield leaves {sh['exposed_m2'] * 1e12:.4g} um2 of junction open; the design's openings "
                f"(each secondary's mask opening, each primary's PD) are {sh['openings_m2'] * 1e12:.4g} um2. "
                "The readout (column circuits, AFEs) is under the top metal: "
                + ", ".join(f"{k} {v['exposed_m2'] * 1e12:.3g} um2" for k, v in sh["blocks"].items()
                            if k != "pixel array") + " open.")
    checked += [Checked("layout_signoff.open_m2", sh["exposed_m2"], "m2", tol_rel=1e-3, tol_abs=1e-15),
                Checked("layout_signoff.open_readout_m2", sum(v["exposed_m2"] for k, v in sh["blocks"].items()
                                                              if k != "pixel array"), "m2", tol_abs=1e-14)]
    exposure = _exposure(d, r)
    pic = plot_exposure(r, exposure, ctx.figure("layout_signoff/shield_open.png"),
                        f"{r['top']}: junction the shield leaves open (red)")
    figures.append(Figure(rel(pic), "What the light shield leaves open: the chip's blocks outlined, the junction "
                                    "no metal covers in red (the pixels' openings)"))
    return Section(TITLE, text=text, tables=tables, figures=figures, checked=checked, files=files,
                   data={"top": r["top"], "shield": sh, "blocks_m2": r["blocks"], "lvs": lvs,
                         "drc": None if drc is None else {**{k: drc[k] for k in ("clean", "total", "by_rule")},
                                                       "deck": f"{d.tech.signoff.drc_deck}: {drc['deck'].rsplit('/', 1)[-1]}"}})


def _foundry_text(r: dict, run_drc: bool, d) -> str:
    """Which of the foundry's chip checks ran (LVS, density, antenna: fd_pv), what they said, and why a check
    was off."""
    if not run_drc:
        return ("The foundry's LVS, density and antenna decks: off in the quick profile (the full profile runs "
                "them on the chip with its fill where the fd_pv decks are installed).")
    if not d.tech.signoff.pv_decks:
        return (f"The foundry's LVS, density and antenna decks: off (technology {d.tech.name} names none, "
                "[signoff] pv_decks): the chip's density rules are not checked.")
    parts = []
    if "fill" in r:
        f = r["fill"]
        parts.append("dummy fill drawn (" + ", ".join(f"{k} {f['before'][k] * 100:.1f} -> {f['after'][k] * 100:.1f} %"
                                                       for k in ("poly", "metal1", "metal2", "metal3")) + ")")
    for key, what in (("foundry_lvs", "foundry LVS"), ("density", "density"), ("antenna", "antenna")):
        v = r.get(key, {})
        if not v.get("run", True):
            parts.append(f"{what} NOT RUN ({v['reason']})")
        elif key == "foundry_lvs":
            parts.append(f"{what}: " + ("Netlists match" if v["match"] else f"{len(v['mismatches'])} mismatch(es)"))
        else:
            parts.append(f"{what}: " + ("clean" if v["clean"] else f"{v['total']} violation(s) ({', '.join(v['by_rule'])})"))
    return "The foundry's chip checks (fd_pv decks): " + "; ".join(parts) + "."


def _rules_run(report: str) -> int:
    """How many rules the deck's report lists (one category each, violated or not)."""
    import xml.etree.ElementTree as ET
    return sum(1 for c in ET.parse(report).getroot().iter("category") if c.findtext("name"))


def _areas(d, r) -> list:
    """Each cell's size, the signed-off array and the design's whole chip (same cells, its rows and
    columns)."""
    size = r["cell_sizes"]
    rows = []
    for block, cells in (("pixel (dual pixel)", ["DUALPIX"]), ("column circuit", ["COLUMN_P", "COLUMN_S"]),
                         ("AFE", ["AFE_P", "AFE_S"]), ("row driver (boosted gate rail)", ["ROWDRV"])):
        for c in (c for c in cells if c in size):
            w, h = size[c]
            rows.append([block, c, w, h, w * h])
    w, h = size["ARRAY"]
    rows.append([f"array {ROWS} x {COLS}", "ARRAY", w, h, w * h])
    w, h = r["size_um"]
    rows.append([f"chip {ROWS} x {COLS} with AFEs", r["top"], w, h, w * h])
    w, h = r["full_chip_um"]
    rows.append([f"chip {d.primary.rows} x {d.primary.cols} (the design's, same cells)", "", w, h, w * h])
    return rows


def _exposure(d, r) -> dict:
    from pathlib import Path
    from ...layout.flow import block_boxes
    from ...layout.shield import exposed_junctions
    return exposed_junctions(Path(r["gds"]), r["top"], d.tech, block_boxes(r))
