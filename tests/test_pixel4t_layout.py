"""The 4T pixel drawn on GF180MCU (``pixelkit layout designs/pixel4t_gf180.toml``): one cell, its stand-in
photodiode (an n-well junction: GF180MCU has no pinned implant, docs/pixel4t.md) and TG, RST, SF, RS.

Independent references: the foundry's DRC deck (gf180mcu.drc, KLayout batch) judges the drawing; KLayout's
LVS extracts the devices from the geometry and compares them with the netlist written from the design's
W / L (a wrong width in the netlist is a mismatch: the check can fail); where the fd_pv decks are
installed (marker ``fd_pv``), the foundry's own LVS deck. The light map's open photodiode junction is the
drawn PPD area less its covered N+ contact.
"""
import json

import pytest

from conftest import ROOT

P4T = ROOT / "designs" / "pixel4t_gf180.toml"


@pytest.fixture(scope="module")
def drawn(tmp_path_factory):
    from conftest import run_cli
    out = tmp_path_factory.mktemp("l4t")
    code, stdout, err = run_cli("layout", P4T, "--out", out, "--drc", "--lvs", "--json")
    return code, json.loads(stdout), out, err


def test_the_4t_cell_is_drc_clean_lvs_matched_and_extracted(drawn):
    code, r, _out, err = drawn
    assert code == 0, err[-2000:]
    assert "stand-in" in r["photodiode"] and "pinning layer" in r["photodiode"]
    s = r["signoff"]
    assert s["drc"]["run"] and s["drc"]["clean"], s["drc"]
    assert s["lvs"]["match"] and s["lvs"]["devices"] == 5 and s["lvs"]["nets"] == 10, s["lvs"]
    assert s["pex"]["run"] and s["pex"]["nets"] == 11
    pd = [j for j in s["lightmap"]["junctions"] if j["kind"] == "photodiode well"]
    drawn_um2 = r["ppd_um"][0] * r["ppd_um"][1]
    assert len(pd) == 1 and 0.95 * drawn_um2 < pd[0]["area_m2"] * 1e12 < drawn_um2
    # the figures docs/pixel4t.md quotes (section "Layout on GF180MCU")
    assert pd[0]["area_m2"] * 1e12 == pytest.approx(15.72, abs=0.005)


def test_lvs_of_the_4t_cell_catches_a_wrong_tg_width(drawn, cli, tmp_path):
    _code, r, _out, _err = drawn
    text = open(r["spice"]).read()
    wrong = tmp_path / "wrong.spice"
    wrong.write_text(text.replace("Mtg pd tg fd vss nfet_03v3 W=0.8u", "Mtg pd tg fd vss nfet_03v3 W=1.2u"))
    assert wrong.read_text() != text
    code, out, err = cli("signoff", r["gds"], "--netlist", wrong, "--top", "PIX4T", "--out", tmp_path / "so",
                         "--skip", "drc,foundry-lvs,pex,lightmap", "--json")
    assert code == 1, err
    assert not json.loads(out)["lvs"]["match"]


def test_a_cell_too_small_for_its_lines_names_the_pitch(cli, tmp_path):
    text = P4T.read_text()
    bad = tmp_path / "p4t.toml"
    bad.write_text(text.replace('pitch = "9 um"', 'pitch = "8 um"'))
    assert 'pitch = "8 um"' in bad.read_text()
    code, _out, err = cli("layout", bad, "--out", tmp_path / "l")
    assert code == 2 and "pixel.pitch" in err and "vrst" in err
    code, _out, err = cli("layout", P4T, "--out", tmp_path / "l2", "--afe")
    assert code == 2 and "--afe" in err


@pytest.mark.fd_pv
def test_the_foundry_lvs_deck_matches_the_4t_cell(drawn, cli, tmp_path):
    _code, r, _out, _err = drawn
    code, out, err = cli("signoff", r["gds"], "--netlist", r["spice"], "--top", "PIX4T", "--out", tmp_path / "so",
                         "--skip", "drc,lvs,pex,lightmap", "--json")
    assert code == 0, err
    assert json.loads(out)["foundry_lvs"]["match"]


@pytest.mark.parametrize("args", [("report", "--quick"), ("netlist",), ("verify",), ("close",)])
def test_post_layout_is_refused_where_a_pixel_read_by_role_has_none(cli, tmp_path, args):
    """--post-layout is refused, never ignored, where the view does not exist: a netlist pixel (its layout is
    the designer's: pixelkit signoff). The 4T takes it everywhere (tests/test_pixel4t_postlayout.py)."""
    design = P4T.with_name("pixel4t_netlist.toml")
    code, _out, err = cli(args[0], design, *args[1:], "--post-layout", "--out", tmp_path / ("r.cir" if args[0] == "netlist"
                                                                                            else "r"))
    assert code == 2 and "--post-layout" in err and "netlist" in err, err
