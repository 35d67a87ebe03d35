"""The column precharge drawn: a design whose read precharges its column lines (``timing.pre_on`` /
``pre_off``, as the reference design's does) has the switch the simulations use
(``circuits.column.precharge``) in its column cells, with its clock ``pre`` on a metal3 line.

Independent judges: the simulations' own column circuit (``column_cell`` with ``precharge``) for
LVS, GlobalFoundries' GF180MCU DRC deck for the geometry. Broken variants LVS must name: the
chip drawn without the switch, and with the switch twice as wide as the netlist's.
"""
from dataclasses import replace

import gdstk
import pytest

from conftest import ROOT
from pixelkit.circuits.column import precharged
from pixelkit.design import load_design
from pixelkit.layout import columns
from pixelkit.layout.flow import write_gds
from pixelkit.layout.library import build_cells, build_chip_cells, to_library
from pixelkit.layout.signoff.lvs import run_lvs

TOP = "CHIP_2X2"


def _read_of(d, ref):
    """``d`` with the row read (precharge included) of ``ref`` (same row times)."""
    return replace(d, primary=replace(d.primary, timing=ref.primary.timing),
                   secondary=replace(d.secondary, timing=ref.secondary.timing))


def _without_precharge(d):
    return replace(d, **{k: replace(getattr(d, k), timing=replace(getattr(d, k).timing, pre_on=None, pre_off=None))
                         for k in ("primary", "secondary")})


def _chip(path, drawn, design):
    """The 2 x 2 chip with its column circuits as ``drawn`` draws it, in ``design``'s GDS."""
    cells, top = build_chip_cells(drawn, 2, 2)
    assert top == TOP
    return write_gds(to_library(design, cells), path)


@pytest.fixture(scope="module")
def chip_gds(tmp_path_factory, ref_design):
    return _chip(tmp_path_factory.mktemp("pre") / "chip.gds", ref_design, ref_design)


@pytest.fixture(scope="module")
def gf_pre(ref_design):
    """The GF180 port read as the reference design reads (both arrays precharged)."""
    return _read_of(load_design(ROOT / "designs" / "dual_pixel_gf180.toml"), ref_design)


def test_reference_chip_draws_the_precharge_and_matches_its_netlist(chip_gds, ref_design):
    """Both arrays precharge; each column cell extracts to 7 devices (bias, load, the two samplers'
    N and P halves, the precharge) and matches its netlist, the chip (pins ``pre_p`` / ``pre_s``) too."""
    assert precharged(ref_design, "primary") and precharged(ref_design, "secondary")
    for cell in ("COLUMN_S", "COLUMN_P", TOP):
        r = run_lvs(chip_gds, cell, ref_design)
        assert r.match, (cell, r.mismatches)
        if cell != TOP:
            assert r.devices == 7, (cell, r.devices)
    labels = {lb.text for c in gdstk.read_gds(str(chip_gds)).cells if c.name == TOP for lb in c.labels}
    assert {"pre_p", "pre_s"} <= labels


def test_lvs_names_a_precharge_missing_from_the_layout(tmp_path, ref_design):
    """The chip drawn as if the design read without a precharge, against the design's netlist."""
    path = _chip(tmp_path / "none.gds", _without_precharge(ref_design), ref_design)
    r = run_lvs(path, TOP, ref_design)
    assert not r.match
    assert any("device pre_col" in m and "missing from the layout" in m for m in r.mismatches), r.mismatches


def test_lvs_names_a_precharge_drawn_at_another_width(tmp_path, ref_design, monkeypatch):
    """The switch drawn at the P-channel samplers' size (2 x sw_w), everything else as designed."""
    monkeypatch.setattr(columns, "PRE", (("pre", "swp", "sw_w", "vss", "pre", "col"),))
    path = _chip(tmp_path / "wide.gds", ref_design, ref_design)
    r = run_lvs(path, TOP, ref_design)
    w = ref_design.pixel.devices.sw_w * 1e6
    assert not r.match
    assert any("device pre_col" in m and f"W {2 * w:.4g} um (layout) vs {w:.4g} um (netlist)" in m
               for m in r.mismatches), r.mismatches


def test_foundry_deck_finds_no_violation_in_the_precharged_gf180_chip(tmp_path, gf_pre):
    """The GF180 chip with its AFE columns and both arrays precharged, and its dual pixel with the
    column devices folded (the precharge's 12 um in fingers, W_); LVS matches both."""
    from pixelkit.layout.signoff.drc import run_drc
    dev = gf_pre.pixel.devices
    wide = replace(gf_pre, pixel=replace(gf_pre.pixel, devices=replace(dev, load_w=12e-6, sw_w=12e-6)))
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    top = gdstk.Cell("TOP")
    x = 0.0
    for prefix, d, (cells, name) in (("G_", gf_pre, build_chip_cells(gf_pre, 2, 2, afe=True, shield="full")),
                                     ("W_", wide, (build_cells(wide), "DUALPIX_COL"))):
        sub = to_library(d, cells)
        one = write_gds(sub, tmp_path / f"{prefix}.gds")
        r = run_lvs(one, name, d)
        assert r.match, (prefix, r.mismatches)
        for c in sub.cells:
            c.name = prefix + c.name
            lib.add(c)
        cell = next(c for c in sub.cells if c.name == prefix + name)
        top.add(gdstk.Reference(cell, (x, 0)))
        (x0, _), (x1, _) = cell.bounding_box()
        x += (x1 - x0) + 20
    lib.add(top)
    lib.write_gds(str(tmp_path / "all.gds"))
    result = run_drc(tmp_path / "all.gds", "TOP", gf_pre.tech, tmp_path / "drc")
    assert "KLayout 0.28.5" in result.klayout
    assert not result.violations, {v.cell: v.rule for v in result.violations}
    names = {c.name for c in lib.cells}
    assert {"G_COLUMN_S", "G_COLUMN_P", "W_COLUMN_S", "G_CHIP_2X2_AFE"} <= names


def test_post_layout_extraction_names_the_precharge_nets(gf_pre):
    """Every net of the precharged dual pixel with its columns is paired with the kit's netlist
    (``net_geometry`` refuses an unmatched one); the clocks carry the benches' names."""
    from pixelkit.layout.pex import chip_geometry
    g = chip_geometry(gf_pre, ("DUALPIX_COL",))["DUALPIX_COL"]
    nets = {n for per_layer in g.wires.values() for n in per_layer}
    assert {"pre_p", "pre_s", "col_p", "col_s0"} <= nets
