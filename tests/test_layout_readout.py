"""The readout drawn and signed off: the AFE cells, the 2 x 2 array with its AFE columns, the
light shield.

Independent judges: GlobalFoundries' GF180MCU DRC deck (Debian's KLayout 0.28.5) for the
geometry; the simulations' own subcircuits (``sc_afe``, ``opamp_ota``, ``column_cell``,
``pixel_array``, connected as ``array_bench`` connects them) for LVS; the design file's PD and
mask-opening sizes for what the shield must leave open. Each check has a broken variant it
must catch: a MIM capacitor without its marker (DRC and LVS), a row line cut from its strap
and two column lines bridged (LVS), a gap cut in the shield over the AFE (the exposure).
"""
import json
import re
from pathlib import Path

import gdstk
import pytest

from conftest import ROOT, layout_variant
from pixelkit.design import load_design
from pixelkit.layout.canvas import Box, Canvas
from pixelkit.layout.flow import write_gds
from pixelkit.layout.library import build_chip_cells, to_library
from pixelkit.layout.shield import exposed_junctions
from pixelkit.layout.signoff.lvs import run_lvs

GF = ROOT / "designs" / "dual_pixel_gf180.toml"
TOP = "CHIP_2X2_AFE"


@pytest.fixture(scope="module")
def gf():
    return load_design(GF)


@pytest.fixture(scope="module")
def chip(gf):
    """The 2 x 2 array of the GF180 design with its AFE columns and the full shield."""
    cells, top = build_chip_cells(gf, 2, 2, afe=True, shield="full")
    assert top == TOP
    return cells


@pytest.fixture(scope="module")
def chip_gds(tmp_path_factory, gf, chip):
    return write_gds(to_library(gf, chip), tmp_path_factory.mktemp("chip") / "chip.gds")


def _without(cv: Canvas, name: str, drop) -> Canvas:
    """A flat copy of ``cv`` named ``name`` without the shapes ``drop`` selects (labels kept)."""
    out = Canvas(name, cv.rules)
    for s in cv.shapes:
        if not drop(s):
            out.add(s.layer, s.box, s.net)
    out.labels = list(cv.labels)
    return out


def _c11_marker(cv: Canvas):
    """The CAP_MK marker over C11 (the top capacitor of AFE_S: the topmost MIM top plate)."""
    top = max((s for s in cv.shapes if s.layer == "mim_top"), key=lambda s: s.box.y1)
    return lambda s: s.layer in ("mim_marker", "mim_l_marker") and s.box.overlaps(top.box)


@pytest.fixture(scope="module")
def drc(tmp_path_factory, gf, ref_design, chip):
    """One deep run of the foundry deck over the chip, the same chip with the thesis's shield
    (``pixels``, its cells prefixed P_), the reference design's chip (c35_thesis, R_), the 1 x 1 chip
    without AFEs (``layout --rows 1 --cols 1``, U_: each strap meets one line there), the GF180
    revision B's 1 x 1 chip (boosted gate drive: its row drivers on the vgate rail, B_), and a copy
    of AFE_S whose C11 lost its CAP_MK / MIM_L_MK markers."""
    from pixelkit.layout.signoff.drc import run_drc
    folder = tmp_path_factory.mktemp("drc")
    lib = to_library(gf, chip)
    bad = _without(chip["AFE_S"], "BAD_MIM", _c11_marker(chip["AFE_S"]))
    cell = bad.to_gdstk(gf.tech, {})
    lib.add(cell)
    top = gdstk.Cell("TOP")
    top.add(gdstk.Reference(next(c for c in lib.cells if c.name == TOP), (0, 0)))
    top.add(gdstk.Reference(cell, (-40, 0)))
    boosted = load_design(ROOT / "designs" / "dual_pixel_gf180_revB.toml")
    for k, (prefix, d, mode, n, afe) in enumerate((("P_", gf, "pixels", 2, True), ("R_", ref_design, "full", 2, True),
                                                   ("U_", gf, "full", 1, False), ("B_", boosted, "full", 1, False))):
        cells, name = build_chip_cells(d, n, n, afe=afe, shield=mode)
        sub = to_library(d, cells)
        for c in sub.cells:
            c.name = prefix + c.name
            lib.add(c)
        top.add(gdstk.Reference(next(c for c in sub.cells if c.name == prefix + name), (100 * (k + 1), 0)))
    lib.add(top)
    path = folder / "all.gds"
    lib.write_gds(str(path))
    return run_drc(path, "TOP", gf.tech, folder), lib


def test_foundry_deck_finds_no_violation_in_the_2x2_array_with_its_afes(drc):
    """Both shields that draw something (full; pixels, with its tie to vss) and both reference
    designs (gf180mcu_3v3, c35_thesis)."""
    result, lib = drc
    assert "KLayout 0.28.5" in result.klayout
    bad = {v.cell: v.rule for v in result.violations if v.cell != "BAD_MIM"}
    assert not bad, f"the GF180MCU deck flags generated cells: {bad}"
    names = {c.name for c in lib.cells}
    assert {"AFE_S", "AFE_P", "SHIELD_READOUT_S", TOP, f"P_{TOP}", f"R_{TOP}"} <= names
    assert "P_SHIELD_READOUT_S" not in names


def test_the_1x1_chip_is_drc_clean(drc):
    """``layout --rows 1 --cols 1``: its ec / tg straps meet one row line each, so each was its via3's
    pad alone, 0.28 x 0.38 um of metal4 under the 0.1444 um2 minimum (M4.3, four markers in CHIP_1X1
    before the chip drew such a strap at the minimum area)."""
    result, lib = drc
    assert "U_CHIP_1X1" in {c.name for c in lib.cells}
    assert not [v for v in result.violations if v.cell.startswith("U_")], result.violations


def test_the_boosted_chip_with_its_row_drivers_is_drc_clean(drc):
    """The gate-drive choice drawn (tests/test_rowdriver.py checks its LVS): the drivers' cell, its two
    n-wells (vdd, vgate) at the different-potential spacing, the bank beside the straps."""
    result, lib = drc
    assert {"B_CHIP_1X1", "B_ROWDRV"} <= {c.name for c in lib.cells}
    assert not [v for v in result.violations if v.cell.startswith("B_")], result.violations


def test_foundry_deck_catches_a_mim_capacitor_without_its_marker(drc):
    result, _ = drc
    assert "MIMTM.7" in result.in_cell("BAD_MIM"), result.in_cell("BAD_MIM")


@pytest.mark.parametrize("top", ["AFE_S", "AFE_P", TOP])
def test_lvs_matches_the_kits_netlist(chip_gds, gf, top):
    r = run_lvs(chip_gds, top, gf)
    assert r.match, r.mismatches


def test_afe_cells_are_at_the_column_pitch_and_hold_the_netlists_values(gf, chip):
    """The AFE is as wide as the column it serves; its MIM plates give C11 - C13 and Cc by the
    model card's law (area and perimeter capacitance, sm141064.ngspice cap_mim_2f0fF)."""
    pa = gf.tech.passives
    for name, pitch in (("AFE_S", gf.secondary.pitch), ("AFE_P", gf.primary.pitch)):
        cv = chip[name]
        assert cv.ports["width"] == round(pitch * 1e9)
        plates = [s.box for s in cv.shapes if s.layer == "mim_top"]
        values = sorted(pa.mim_c_area * b.w * b.h * 1e-18 + pa.mim_c_perimeter * 2 * (b.w + b.h) * 1e-9
                        for b in plates)
        assert values == pytest.approx(sorted([gf.afe.c11, gf.afe.c12, gf.afe.c13, 1e-12]), rel=1e-3)
        assert all(b.x0 >= 0 and b.x1 <= cv.ports["width"] for b in plates)


def test_lvs_catches_a_mim_capacitor_without_its_marker(tmp_path, gf, chip):
    bad = _without(chip["AFE_S"], "AFE_S", _c11_marker(chip["AFE_S"]))
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    lib.add(bad.to_gdstk(gf.tech, {}))
    path = tmp_path / "m.gds"
    lib.write_gds(str(path))
    r = run_lvs(path, "AFE_S", gf)
    assert not r.match and any("device 11 " in m and "missing" in m for m in r.mismatches), r.mismatches


def _chip_variant(tmp_path, gf, chip, edit) -> Path:
    """The chip's GDS with ``edit(chip_cell_shapes)`` applied to the chip cell's own shapes."""
    return layout_variant(tmp_path / "v.gds", gf, chip, TOP, edit)


def test_lvs_catches_a_row_line_cut_from_its_strap(tmp_path, gf, chip):
    """The via joining row 1's ec_s line to the global ec_s strap removed: that row's EC gates
    are on a net of their own."""
    strap_x = chip[TOP].ports["straps"]["ec_s"]
    vias = [s for s in chip[TOP].shapes if s.layer == "via3" and s.net == "ec_s" and s.box.cx == strap_x]
    assert len(vias) == 2
    cut = max(vias, key=lambda s: s.box.cy)
    path = _chip_variant(tmp_path, gf, chip, lambda shapes: [s for s in shapes if s is not cut])
    r = run_lvs(path, TOP, gf)
    assert not r.match and r.mismatches, r.mismatches


def test_lvs_catches_a_column_line_shorted_to_its_neighbour(tmp_path, gf, chip):
    """A metal4 bridge between the first two secondary column lines, in the first row of secondaries
    (where no other metal4 runs between them)."""
    dual = chip["DUALPIX"]
    xa, xb = dual.ports["col_s0"][1], dual.ports["col_s1"][1]
    y = round(gf.secondary.pitch * 1e9) // 2
    between = [s for s in dual.shapes_on("metal4") if not s.net.startswith("#") and s.box.y0 <= y <= s.box.y1
               and xa < s.box.cx < xb]
    assert not between, between
    p = chip[TOP].ports
    x0, y0 = p["margin"], p["hb"]
    bridge = Box(x0 + xa, y0 + y - 140, x0 + xb, y0 + y + 140)
    path = _chip_variant(tmp_path, gf, chip, lambda shapes: shapes + [type(shapes[0])("metal4", bridge, "x")])
    r = run_lvs(path, TOP, gf)
    assert not r.match and r.mismatches, r.mismatches


# ---------------------------------------------------------------- the shield -------------------

def _openings(d, n_pixels):
    """What the design asks the shield to leave open: each secondary's mask opening, each
    (unmasked) primary's whole PD - from the design file, not from the layout."""
    return n_pixels * (d.primary.pd_width * d.primary.pd_height + d.secondary_per_pixel * d.secondary.mask_opening)


def test_full_shield_leaves_open_only_the_mask_openings(chip_gds, gf, chip):
    ex = exposed_junctions(chip_gds, TOP, gf.tech, chip[TOP].ports["blocks"])
    for block in ("column circuits", "AFE", "periphery"):
        assert ex[block]["exposed_m2"] == 0, (block, ex[block]["exposed_m2"])
    assert ex["AFE"]["junction_m2"] > 1e-9      # there is junction under the shield to protect
    total = sum(v["exposed_m2"] for v in ex.values())
    assert total == pytest.approx(_openings(gf, 4), rel=0.01)


def test_a_gap_in_the_shield_over_the_afe_is_reported_as_exposed_afe_area(tmp_path, gf, chip):
    """A 3 x 3 um hole cut in the shield over the op-amp's output devices of AFE_S (a copy of the
    shield cell with the hole, placed as the original). The exposed AFE area must equal, in each of
    the 6 AFE_S, the junction under the hole that no lower metal covers - computed here with gdstk
    from the AFE cell's own polygons, not by the kit's exposure code."""
    afe = chip["AFE_S"]
    big = max((s for s in afe.shapes if s.layer == "active"), key=lambda s: s.box.w * s.box.h)
    hole = Box(big.box.x0, big.box.cy - 1500, big.box.x0 + 3000, big.box.cy + 1500)
    sh = chip["SHIELD_READOUT_S"]
    keep = list(sh.shapes)
    cut = []
    for s in sh.shapes:
        if s.box.overlaps(hole):
            for piece in _minus(s.box, hole):
                cut.append(type(s)(s.layer, piece, s.net))
        else:
            cut.append(s)
    sh.shapes = cut
    try:
        path = write_gds(to_library(gf, chip), tmp_path / "gap.gds")
    finally:
        sh.shapes = keep
    ex = exposed_junctions(path, TOP, gf.tech, chip[TOP].ports["blocks"])
    lib = gdstk.read_gds(str(path))
    cell = next(c for c in lib.cells if c.name == "AFE_S")
    polys = cell.get_polygons()

    def on(name):
        lay = gf.tech.layer(name)
        return [p for p in polys if (p.layer, p.datatype) == (lay.layer, lay.datatype)]
    junction = gdstk.boolean(on("active"), on("nwell"), "or")
    lower = [p for m in ("metal1", "metal2", "metal3", "metal4") for p in on(m)]
    window = gdstk.rectangle((hole.x0 / 1000, hole.y0 / 1000), (hole.x1 / 1000, hole.y1 / 1000))
    expect = sum(p.area() for p in gdstk.boolean(gdstk.boolean(junction, window, "and"), lower, "not")) * 1e-12
    assert expect > 0.5e-12
    assert ex["AFE"]["exposed_m2"] == pytest.approx(6 * expect, rel=1e-3)
    assert ex["column circuits"]["exposed_m2"] == 0


def _minus(b: Box, h: Box):
    out = []
    for piece in (Box(b.x0, b.y0, b.x1, h.y0), Box(b.x0, h.y1, b.x1, b.y1), Box(b.x0, max(b.y0, h.y0), h.x0, min(b.y1, h.y1)),
                  Box(h.x1, max(b.y0, h.y0), b.x1, min(b.y1, h.y1))):
        if piece.w > 0 and piece.h > 0:
            out.append(piece)
    return out


# ---------------------------------------------------------------- command line ------------------

def test_layout_cli_pixels_shield_leaves_the_readout_open(tmp_path, cli):
    """The chip of [Thesis2019]: the pixels shielded, the readout open. The pixels' exposure is what the
    design asks; the AFE and column circuits show their junctions."""
    code, out, err = cli("layout", GF, "--afe", "--shield", "pixels", "--lvs", "--no-pictures", "--json",
                         "--out", tmp_path)
    assert code == 0, err
    r = json.loads(out)
    assert r["top"] == TOP and r["lvs"]["match"], r["lvs"]
    sh = r["shield"]
    assert sh["mode"] == "pixels"
    assert sh["blocks"]["pixel array"]["exposed_m2"] == pytest.approx(sh["openings_m2"], rel=0.01)
    for block in ("AFE", "column circuits"):
        assert sh["blocks"][block]["exposed_m2"] > 0.3 * sh["blocks"][block]["junction_m2"] > 0
    spice = Path(r["spice"][TOP]).read_text()
    assert re.search(r"^\.subckt AFE_S in out vref p1 p1b p2 p2b vdd nb vss$", spice, re.M)
    afe = Path(r["spice"]["AFE_S"]).read_text()   # the drawn plates and resistor, for any LVS deck
    assert re.search(r"^C11 in vm cap_mim_2f0_m4m5_noshield W=\S+u L=\S+u$", afe, re.M)
    assert re.search(r"^Rop_z op_n2 op_nz vss ppolyf_u W=0\.8u L=\S+u$", afe, re.M)


def test_array_larger_than_the_design_is_refused(tmp_path, cli):
    code, out, err = cli("layout", GF, "--rows", "28", "--out", tmp_path / "o")
    assert code == 2 and "--rows" in err and "27" in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_an_afe_capacitor_under_the_mim_minimum_is_refused_before_anything_is_written(tmp_path, cli):
    bad = tmp_path / "d.toml"
    bad.write_text(re.sub(r'^c11 = "500 fF"', 'c11 = "20 fF"', GF.read_text(), flags=re.M))
    code, out, err = cli("layout", bad, "--afe", "--json", "--out", tmp_path / "o")
    assert code == 2, err
    e = json.loads(out)
    assert e["field"] == "afe.c11" and e["value"] == "20 fF" and "at least" in e["allowed"]
    assert not (tmp_path / "o").exists()


# ---------------------------------------------------------------- the report ----------------------

def test_a_violation_is_pictured_where_the_deck_found_it(drc, gf, tmp_path):
    """The report's picture of a DRC marker: the layers of the flagged cell around the marker's
    own coordinates (the BAD_MIM's MIMTM.7 marker lies on the plate that lost its CAP_MK)."""
    from pixelkit.layout.render import plot_violation
    result, _ = drc
    v = next(v for v in result.violations if v.cell == "BAD_MIM" and v.rule == "MIMTM.7")
    nums = [float(x) for x in re.findall(r"-?\d+(?:\.\d+)?", v.where)]
    assert max(nums[1::2]) > 300     # C11 is the topmost plate of the 337 um tall AFE_S
    png = plot_violation(Path(result.report).parent / "all.gds", v.cell, v.where, gf.tech, tmp_path / "v.png", v.rule)
    assert png.read_bytes()[:4] == b"\x89PNG" and png.stat().st_size > 5000


def test_report_section_signs_off_and_shows_the_open_junction(tmp_path, gf):
    """The "Layout sign-off" section as the full report builds it (the foundry deck, LVS, the
    shield; the quick profile leaves the deck out): its tables, picture and checked figures."""
    from pixelkit.report.sections import Context
    from pixelkit.report.sections.layout_signoff import build
    s = build(Context(gf, tmp_path, quick=False))
    assert s.available, s.why
    tables = {t.name: t for t in s.tables}
    assert tables["layout_signoff_drc"].rows == [["(none)", 0, "", "", ""]]
    assert re.search(r"gf180mcu\.drc \(KLayout 0\.28\.5, deep mode, \d{3} rules in its report\) on CHIP_2X2_AFE: "
                     r"no violation", " ".join(s.text)), s.text
    assert tables["layout_signoff_lvs"].rows[0][:2] == [TOP, "match"]
    areas = {r[1]: r for r in tables["layout_signoff_areas"].rows}
    assert areas["AFE_S"][2] == pytest.approx(gf.secondary.pitch * 1e6) and areas["AFE_P"][2] == pytest.approx(24)
    assert areas["DUALPIX"][4] == pytest.approx(24 * 32)
    shield = {r[0]: r for r in tables["layout_signoff_shield"].rows}
    assert shield["AFE"][2] == 0 and shield["AFE"][1] > 0
    assert shield["all"][2] == pytest.approx(_openings(gf, 4) * 1e12, rel=0.01)
    assert (tmp_path / s.figures[0].file).stat().st_size > 5000
    checked = {c.name: c for c in s.checked}
    assert {"layout_signoff.lvs_match", "layout_signoff.open_m2"} <= set(checked)
    assert checked["layout_signoff.drc_violations"].value == 0
