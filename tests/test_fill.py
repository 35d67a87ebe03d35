"""Dummy fill for the foundry's density rules (``pixelkit layout --fill``), and the density and antenna decks.

Independent judges: the foundry's DRC deck (the fill must not break a rule), the kit's LVS (the fill
must not join a net), the geometry read back (coverage per layer as the density deck counts it; the
junction the shield leaves open, which fill must not shade), and - where the fd_pv decks are installed
(marker ``fd_pv``) - the foundry's density and antenna decks themselves, each shown to fail for the
right reason (the unfilled chip; a gate under a large metal plate).
"""
from pathlib import Path

import gdstk
import pytest

from conftest import ROOT

GF = ROOT / "designs" / "dual_pixel_gf180.toml"


@pytest.fixture(scope="module")
def chips(tmp_path_factory):
    """The GF180 2 x 2 chip with its AFEs, drawn without and with fill."""
    from pixelkit.design import load_design
    from pixelkit.layout.flow import layout_design
    d = load_design(GF)
    out = {}
    for fill in (False, True):
        folder = tmp_path_factory.mktemp("fill" if fill else "nofill")
        out[fill] = layout_design(d, folder, 2, 2, pictures=False, afe=True, fill=fill, lvs=fill)
    return d, out


def test_fill_reaches_every_density_figure_and_stays_off_the_light_path(chips):
    from pixelkit.layout.fill import TARGET
    d, r = chips
    f = r[True]["fill"]
    assert all(f["before"][k] < TARGET[k] for k in ("poly", "metal1", "metal2", "metal3")), f["before"]
    assert all(f["after"][k] >= TARGET[k] for k in TARGET), f["after"]
    assert f["after"]["metal1"] == pytest.approx(0.483, abs=0.01) and f["after"]["poly"] == pytest.approx(0.163, abs=0.01)
    # the junction no metal covers: the same with the fill (the photodiodes' openings), read back by gdstk
    assert r[True]["shield"]["exposed_m2"] == pytest.approx(r[False]["shield"]["exposed_m2"], rel=1e-9, abs=0)
    lib = gdstk.read_gds(r[True]["gds"])
    fill = next(c for c in lib.cells if c.name.endswith("_FILL"))
    sq = fill.get_polygons(layer=34, datatype=4) + fill.get_polygons(layer=30, datatype=0)
    opening = [p for c in lib.cells if c.name == r[True]["top"] for p in c.get_polygons(layer=153, datatype=51)]
    m5 = [p for c in lib.cells if c.name == r[True]["top"] for p in c.get_polygons(layer=81, datatype=0)]
    light = gdstk.boolean(opening, m5, "not")
    assert sq and not gdstk.boolean(sq, light, "and"), "fill over an open photodiode"
    assert r[True]["lvs"]["match"], r[True]["lvs"]["mismatches"]       # floating fill joins no net


def test_the_filled_chip_passes_the_foundry_drc_deck(chips, tmp_path):
    from pixelkit.layout.signoff.drc import run_drc
    d, r = chips
    res = run_drc(Path(r[True]["gds"]), r[True]["top"], d.tech, tmp_path)
    assert res.clean, res.by_rule()


@pytest.mark.fd_pv
def test_density_fails_unfilled_and_passes_filled(chips, tmp_path):
    from pixelkit.layout.signoff.foundry import run_chip_drc
    d, r = chips
    bare = run_chip_drc(Path(r[False]["gds"]), r[False]["top"], d.tech, tmp_path / "a", "density")
    assert {"PL.8", "M1.4", "M2.4", "M3.4"} <= set(bare.by_rule()), bare.by_rule()
    filled = run_chip_drc(Path(r[True]["gds"]), r[True]["top"], d.tech, tmp_path / "b", "density")
    assert filled.clean, filled.by_rule()


@pytest.mark.fd_pv
def test_antenna_passes_the_chip_and_catches_a_gate_under_a_large_plate(chips, tmp_path):
    """The chip: clean. A broken variant: a 0.28 x 0.5 um gate whose poly reaches a 60 x 60 um metal1 plate
    through a contact (metal1 perimeter x 0.54 um against the gate's 0.14 um2: far over ANT.16's 400)."""
    from pixelkit.layout.signoff.foundry import run_chip_drc
    d, r = chips
    assert run_chip_drc(Path(r[True]["gds"]), r[True]["top"], d.tech, tmp_path / "a", "antenna").clean
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    c = gdstk.Cell("ANT")
    for (l, dt), box in (((22, 0), (0, 0, 0.5, 2)), ((32, 0), (-0.3, -0.3, 0.8, 2.3)), ((30, 0), (-0.5, 0.86, 1.5, 1.14)),
                         ((30, 0), (1.2, 0.7, 1.7, 1.3)), ((33, 0), (1.34, 0.89, 1.56, 1.11)),
                         ((34, 0), (1.1, 0.6, 61.1, 60.6))):
        c.add(gdstk.rectangle(box[:2], box[2:], layer=l, datatype=dt))
    lib.add(c)
    path = tmp_path / "ant.gds"
    lib.write_gds(str(path))
    bad = run_chip_drc(path, "ANT", d.tech, tmp_path / "b", "antenna")
    assert any(rule.startswith("ANT.") for rule in bad.by_rule()), bad.by_rule()
