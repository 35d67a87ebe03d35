"""``pixelkit signoff``: a layout the kit did not draw (or drew and the designer edited) through the
foundry's DRC, the kit's LVS against the designer's netlist, extraction, the post-layout netlist and
the light map - the same results as the kit's own flow on a drawn cell, each edit of the tutorial
caught or measured, and every bad layout refused before any deck runs.

Independent judges: the foundry's DRC deck; the kit's own flow on the drawn cell (``layout``'s DRC,
``pex.nets.net_geometry`` with the kit's netlist) for the equality; ngspice for the post-layout netlist.
"""
import gzip
import json
import subprocess
import zlib
from pathlib import Path

import gdstk
import pytest

from conftest import ROOT
from pixelkit.errors import ConfigError, PixelkitError
from pixelkit.layout.anylayout import signoff
from pixelkit.layout.signoff import fdpv

GF = ROOT / "designs" / "dual_pixel_gf180.toml"
EDIT = ROOT / "examples" / "edit_layout.py"
FOUNDRY = fdpv.check() is None            # the fd_pv decks installed here (else foundry LVS: NOT RUN, exit 5)


@pytest.fixture(scope="module")
def gf():
    from pixelkit.design import load_design
    return load_design(GF)


@pytest.fixture(scope="module")
def drawn(tmp_path_factory, gf):
    """The GF180 reference chip (2 x 2, AFEs, full shield) as `pixelkit layout --afe` writes it."""
    from pixelkit.layout.flow import layout_design
    folder = tmp_path_factory.mktemp("drawn")
    r = layout_design(gf, folder, 2, 2, pictures=False, afe=True)
    return Path(r["gds"]), {k: Path(v) for k, v in r["spice"].items()}


def _edited(tmp_path, gds, *edits) -> Path:
    out = tmp_path / f"{'_'.join(edits)}.gds"
    import sys
    subprocess.run([sys.executable, str(EDIT), str(gds), str(out), *edits], check=True, capture_output=True)
    return out


# ------------------------------------------------------------ the same results as the kit's own flow --

@pytest.fixture(scope="module")
def col_signoff(tmp_path_factory, drawn, gf):
    """One sign-off of the drawn DUALPIX_COL (every check), shared."""
    gds, spice = drawn
    out = tmp_path_factory.mktemp("so_col")
    return signoff(gds, spice["DUALPIX_COL"], gf.tech, out, "DUALPIX_COL"), out


def test_signoff_of_a_drawn_cell_equals_the_kits_own_flow(col_signoff, drawn, gf):
    from pixelkit.layout.pex.capacitance import capacitances
    from pixelkit.layout.pex.light import exposed
    from pixelkit.layout.pex.nets import net_geometry
    r, out = col_signoff
    gds, _ = drawn
    assert r["drc"]["clean"] and r["drc"]["total"] == 0 and "KLayout 0.28.5" in r["drc"]["klayout"]
    assert r["lvs"]["match"], r["lvs"]["mismatches"]
    assert r["foundry_lvs"]["match"] if FOUNDRY else r["foundry_lvs"]["run"] is False
    assert r["exit_status"] == (0 if FOUNDRY else 5)
    own = net_geometry(gds, "DUALPIX_COL", gf)           # the kit's path: its own netlist of the cell
    cpl = capacitances(own, gf.tech.stack)
    rows = (out / "DUALPIX_COL.caps.csv").read_text().splitlines()[1:]
    table = {(a, b): float(c) for a, b, c in (x.split(",") for x in rows)}
    expect = {k: v for k, v in cpl.items() if v > 1e-19}
    assert set(table) == set(expect) and len(table) > 300
    assert all(table[k] == pytest.approx(v, rel=1e-5, abs=0) for k, v in expect.items())   # 7 digits written
    assert r["pex"]["total_F"]["pix.s0.fd"] == pytest.approx(cpl.total("pix.s0.fd"), rel=1e-12, abs=0)
    js = exposed(own, "pixels")
    assert r["lightmap"]["open_m2"] == pytest.approx(sum(j.area_m2 for j in js), rel=1e-12, abs=0)
    assert json.loads((out / "signoff.json").read_text())["exit_status"] == r["exit_status"]


def test_the_post_layout_netlist_runs_in_ngspice(tmp_path, drawn, gf):
    """The designer's netlist with X-instances of GF180's MOS subcircuits (as Xschem writes it): the
    post-layout netlist keeps those cards, adds the extracted capacitors, and ngspice solves it."""
    gds, spice = drawn
    text = spice["SECONDARY"].read_text().replace("\nM", "\nXM")
    net = tmp_path / "sec.spice"
    net.write_text(text)
    r = signoff(gds, net, gf.tech, tmp_path / "o", "SECONDARY", skip=("drc", "foundry-lvs", "lightmap"))
    post = Path(r["pex"]["post_layout_netlist"]).read_text()
    assert "XMtg fd tg pd vss nfet_03v3" in post and post.count("\nCpex") == r["pex"]["couplings"]
    inc = "\n".join(i.line(str(i.folder)) for i in gf.tech.models.includes())
    deck = tmp_path / "op.cir"
    deck.write_text(f"post-layout secondary\n{inc}\n{post}\nX1 vdd vpdr vrst ec tg rst rs col 0 SECONDARY_post\n"
                    "Vdd vdd 0 3.3\nVpdr vpdr 0 2.5\nVrst vrst 0 2.5\nVec ec 0 0\nVtg tg 0 0\nVrst2 rst 0 3.3\n"
                    "Vrs rs 0 3.3\nIcol col 0 1u\nDpd 0 X1.pd dmod\n.model dmod d\n.op\n.end\n")
    p = subprocess.run(["ngspice", "-b", str(deck)], capture_output=True, text=True, cwd=tmp_path, timeout=120)
    import re
    fd = re.search(r"^\s*x1\.fd\s+(\S+)", p.stdout, re.M)
    assert p.returncode == 0 and fd and "Error:" not in p.stdout + p.stderr, p.stdout[-2000:] + p.stderr[-2000:]
    assert 2.0 < float(fd.group(1)) < 2.5          # FD reset through RST (gate 3.3 V) toward vrst = 2.5 V


# ------------------------------------------------------------------ the tutorial's edits, each caught --

def test_a_removed_via_is_an_lvs_mismatch_named_by_its_net(tmp_path, drawn, gf):
    gds, spice = drawn
    bad = _edited(tmp_path, gds, "remove-via")
    r = signoff(bad, spice["CHIP_2X2_AFE"], gf.tech, tmp_path / "o", "CHIP_2X2_AFE",
                skip=("drc", "pex", "lightmap", "foundry-lvs"))
    assert not r["lvs"]["match"] and r["exit_status"] == 1
    assert any(m.startswith("SECONDARY: pin tg unmatched") for m in r["lvs"]["mismatches"]), r["lvs"]["mismatches"]


def test_a_moved_line_is_caught_by_drc_and_measured_by_extraction_an_opened_shield_by_the_light_map(
        tmp_path, drawn, gf):
    """The RST line moved 0.1 um toward VRST (DRC: M3.2a; extraction: C(rst, vrst) of the secondary up)
    and a strip of the shield over the secondary columns' P-channel samplers opened (light map: their
    junctions open; through the readout, an output error far above the read noise), in one run."""
    from pixelkit.layout.pex import gds_geometry
    from pixelkit.layout.pex.light import exposed
    gds, spice = drawn
    bad = _edited(tmp_path, gds, "move-line", "open-shield")
    r = signoff(bad, spice["SECONDARY"], gf.tech, tmp_path / "o", "SECONDARY", skip=("foundry-lvs", "lightmap"))
    assert r["drc"]["by_rule"].get("M3.2a", 0) >= 1 and "V2.4a" in r["drc"]["by_rule"], r["drc"]["by_rule"]
    assert r["lvs"]["match"] and r["exit_status"] == 1
    before = signoff(gds, spice["SECONDARY"], gf.tech, tmp_path / "o0", "SECONDARY",
                     skip=("drc", "foundry-lvs", "lightmap"))
    c0 = _pair(tmp_path / "o0" / "SECONDARY.caps.csv", "rst", "vrst")
    c1 = _pair(tmp_path / "o" / "SECONDARY.caps.csv", "rst", "vrst")
    assert before["lvs"]["match"] and c1 > 1.2 * c0, (c0, c1)
    # the shield strip: the chip's light map through its own metal
    geo0 = gds_geometry(gf, gds, ("DUALPIX_COL",), context="CHIP_2X2_AFE")["DUALPIX_COL"]
    geo1 = gds_geometry(gf, bad, ("DUALPIX_COL",), context="CHIP_2X2_AFE")["DUALPIX_COL"]
    open0 = {j.net for j in exposed(geo0, "pixels")}
    open1 = {(j.net, j.kind) for j in exposed(geo1, "pixels")}
    assert open0 == {"pix.p.pd", "pix.s0.pd", "pix.s1.pd", "pix.s2.pd"}
    assert ("out_s0", "psd") in open1 and ("col_s0", "psd") in open1 and not any(n == "out_p" for n, _ in open1)


def _pair(path: Path, a: str, b: str) -> float:
    for line in path.read_text().splitlines()[1:]:
        x, y, c = line.split(",")
        if {x, y} == {a, b}:
            return float(c)
    return 0.0


def test_the_design_takes_the_edited_layout_for_post_layout(tmp_path, drawn, gf):
    """A design naming the edited GDS in [layout] gds: its post-layout view is extracted from that file
    (the moved RST line's coupling into the secondary's FD differs from the drawn layout's)."""
    from dataclasses import replace
    from pixelkit.design import LayoutRef
    from pixelkit.layout.pex.overlay import from_gds, post_layout_view
    gds, _ = drawn
    bad = _edited(tmp_path, gds, "move-line")
    d = replace(gf, layout=LayoutRef(str(bad)), source=str(tmp_path / "d.toml"))
    view = post_layout_view(d, afe=False).post_layout
    assert view.source.startswith(f"extracted from {bad}")
    drawn_view = from_gds(gf, gds, afe=False)

    def rst_vrst(v):
        return sum(c for a, b, c in v.cells["dualpix"] if {a, b} == {"rst_s", "vrst"})
    assert rst_vrst(view) > 1.2 * rst_vrst(drawn_view) > 0


# ---------------------------------------------------------------- bad layouts, refused before any deck --

def _gds(tmp_path, name, build) -> Path:
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    build(lib)
    path = tmp_path / name
    lib.write_gds(str(path))
    return path


def _cell(lib, name, shapes=(), labels=()):
    c = gdstk.Cell(name)
    for (l, d), box in shapes:
        c.add(gdstk.rectangle(box[:2], box[2:], layer=l, datatype=d))
    for text, (l, d), xy in labels:
        c.add(gdstk.Label(text, xy, layer=l, texttype=d))
    lib.add(c)
    return c


NET = ".subckt TOP a vss\n.ends TOP\n"


@pytest.mark.parametrize("case,content,found", [
    ("empty", b"", "an empty file"),
    ("random", bytes(range(256)) * 40, "a file starting with bytes 00 01 02"),
    ("dxf", b"0\nSECTION\n2\nHEADER\n", "a file starting with bytes 30 0a"),
])
def test_not_a_layout_is_refused(tmp_path, gf, case, content, found):
    p = tmp_path / f"{case}.gds"
    p.write_bytes(content)
    net = tmp_path / "n.spice"
    net.write_text(NET)
    with pytest.raises(ConfigError, match=found):
        signoff(p, net, gf.tech, tmp_path / "o")
    assert not (tmp_path / "o").exists()


def test_truncated_and_compressed_bomb_layouts_are_refused(tmp_path, drawn, gf):
    gds, spice = drawn
    data = gds.read_bytes()
    cut = tmp_path / "cut.gds"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(ConfigError, match="stops after .* without its ENDLIB record .truncated."):
        signoff(cut, spice["SECONDARY"], gf.tech, tmp_path / "o")
    bomb = tmp_path / "bomb.gds.gz"
    z = zlib.compressobj(1, zlib.DEFLATED, 16 + zlib.MAX_WBITS)
    with open(bomb, "wb") as f:
        f.write(z.compress(data[:4]))
        zeros = bytes(1 << 20)
        for _ in range(300):                     # 300 MiB of zeros in ~300 kB
            f.write(z.compress(zeros))
        f.write(z.flush())
    assert bomb.stat().st_size < 2 << 20
    with pytest.raises(ConfigError, match="gzip data expanding past 256 MiB"):
        signoff(bomb, spice["SECONDARY"], gf.tech, tmp_path / "o")
    good = tmp_path / "good.gds.gz"
    good.write_bytes(gzip.compress(data))              # a compressed layout is read as it is
    from pixelkit.layout.signoff.gds_in import read_layout
    assert read_layout(good, gf.tech, "SECONDARY", tmp_path).top == "SECONDARY"
    assert not (tmp_path / "o").exists()


def test_top_cells_none_several_or_absent(tmp_path, gf):
    net = tmp_path / "n.spice"
    net.write_text(NET)
    none = _gds(tmp_path, "none.gds", lambda lib: None)
    with pytest.raises(ConfigError, match=r"cells = '\(none\)'"):
        signoff(none, net, gf.tech, tmp_path / "o")
    two = _gds(tmp_path, "two.gds", lambda lib: (_cell(lib, "A"), _cell(lib, "B")))
    with pytest.raises(ConfigError, match=r"--top = '\(not given\)': expected one of its top cells, A, B"):
        signoff(two, net, gf.tech, tmp_path / "o")
    with pytest.raises(ConfigError, match=r"--top = 'C': expected a cell of the layout \(A, B\)"):
        signoff(two, net, gf.tech, tmp_path / "o", top="C")


def test_an_unmapped_layer_a_stray_label_and_a_netlist_without_the_cell(tmp_path, gf):
    m1 = (34, 0)
    net = tmp_path / "n.spice"
    net.write_text(NET)
    odd = _gds(tmp_path, "odd.gds", lambda lib: _cell(lib, "TOP", [(m1, (0, 0, 1, 1)), ((99, 7), (0, 0, 1, 1))]))
    with pytest.raises(ConfigError, match=r"layer 99/7 = 'shapes in cell TOP': expected layers of technology "
                                          r"gf180mcu_3v3"):
        signoff(odd, net, gf.tech, tmp_path / "o")
    stray = _gds(tmp_path, "stray.gds", lambda lib: _cell(lib, "TOP", [(m1, (0, 0, 1, 1))],
                                                           [("a", (34, 10), (0.5, 0.5)), ("b", (34, 10), (5, 5))]))
    with pytest.raises(ConfigError, match=r"label 'b' = 'on metal1_label at \(5, 5\) um of cell TOP, over no "
                                          r"metal1 shape'"):
        signoff(stray, net, gf.tech, tmp_path / "o")
    ok = _gds(tmp_path, "ok.gds", lambda lib: _cell(lib, "TOP", [(m1, (0, 0, 1, 1))], [("a", (34, 10), (0.5, 0.5))]))
    other = tmp_path / "other.spice"
    other.write_text(".subckt CELL a vss\n.ends CELL\n")
    with pytest.raises(PixelkitError, match=r"no \.subckt TOP .*; its subcircuits: CELL"):
        signoff(ok, other, gf.tech, tmp_path / "o")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("card,found", [
    ("M1 a a vss vss nfet_05v0 W=1u L=1u", "device M1 = 'nfet_05v0': expected a device the extraction of "
                                          "technology gf180mcu_3v3 produces"),
    ("C1 a vss cap_mim_2f0_m4m5_noshield W=10u L=10u", "device C1 of TOP = 'cap_mim_2f0_m4m5_noshield': expected a "
                                                        "device the layout can have: cell TOP of .* has no mim_top"),
    (".include /etc/passwd", "only .subckt, .ends, .end, .global dot cards"),
    ("V1 a vss 1", "an M, X, D, C or R card"),
    ("M1 a a vss vss nfet_03v3 L=1u", r"device M1 = '\(no W=\)'"),
])
def test_a_netlist_naming_a_device_the_layout_lacks_or_a_card_it_does_not_read(tmp_path, gf, card, found):
    ok = _gds(tmp_path, "ok.gds", lambda lib: _cell(lib, "TOP", [((34, 0), (0, 0, 1, 1)), ((22, 0), (2, 2, 3, 3)),
                                                                  ((30, 0), (2, 2, 3, 3))],
                                                     [("a", (34, 10), (0.5, 0.5))]))
    net = tmp_path / "n.spice"
    net.write_text(f".subckt TOP a vss\n{card}\n.ends TOP\n")
    with pytest.raises(ConfigError, match=found):
        signoff(ok, net, gf.tech, tmp_path / "o")
    assert not (tmp_path / "o").exists()


def test_cli_bad_layout_exit_2_before_any_deck(tmp_path, cli):
    p = tmp_path / "t.gds"
    p.write_bytes(b"\x00\x06\x00\x02\x00\x03" + b"\x00" * 10)
    net = tmp_path / "n.spice"
    net.write_text(NET)
    code, out, err = cli("signoff", p, "--netlist", net, "--out", tmp_path / "o")
    assert code == 2 and "t.gds: layout" in err and "truncated" in err and not (tmp_path / "o").exists()
    code, out, err = cli("signoff", p, "--netlist", net, "--skip", "drc,nothing")
    assert code == 2 and "--skip = 'nothing'" in err


def test_nothing_is_written_through_a_link_in_the_output_folder(tmp_path, drawn, gf):
    gds, spice = drawn
    out = tmp_path / "o"
    out.mkdir()
    victims = {}
    for name in ("SECONDARY.caps.csv", "signoff.json", "SECONDARY.lvsdb", "SECONDARY.post.spice"):
        v = tmp_path / f"victim_{name}"
        v.write_text("keep")
        (out / name).symlink_to(v)
        victims[name] = v
    r = signoff(gds, spice["SECONDARY"], gf.tech, out, "SECONDARY", skip=("drc", "foundry-lvs"))
    assert r["lvs"]["match"]
    for name, v in victims.items():
        assert v.read_text() == "keep" and not (out / name).is_symlink() and (out / name).stat().st_size > 10
