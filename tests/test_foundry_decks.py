"""The foundry's own decks in the flow: GF180MCU fd_pv LVS (deep mode, the hierarchy, every label kept),
density and antenna - fetched at a pinned commit, every file checked by sha256, patched by the
patches in ``pixelkit/layout/signoff/fd_pv`` (each checked before it is applied).

The tests marked ``fd_pv`` run the decks: where they are not installed (no github.com at set-up and
no local checkout given) they are deselected by the marker, and pytest's summary says why
(tests/conftest.py). The others check the pinning, the patches and the refusals on synthetic decks,
everywhere.
"""
import hashlib
from dataclasses import replace
from pathlib import Path

import gdstk
import pytest

from conftest import REF, ROOT
from pixelkit.layout.canvas import Canvas, Shape
from pixelkit.layout.signoff import fdpv
from pixelkit.layout.signoff.decks import DeckError

GF = ROOT / "designs" / "dual_pixel_gf180.toml"


# ------------------------------------------------------------- pinning and patches, no deck needed --

def test_every_patch_names_a_pinned_file_and_says_why():
    pins = fdpv.pinned()
    assert len(pins) == 30 and all(len(s) == 64 for s in pins.values())
    assert fdpv.LVS_DECK in pins and fdpv.DENSITY_DECK in pins and fdpv.ANTENNA_DECK in pins
    ps = fdpv.patches()
    assert [p.name for p in ps] == ["0001-photodiode-cathode", "0002-substrate-taps"]
    for p in ps:
        assert p.file in pins and len(p.reason) > 200 and p.changes and len(p.sha256_after) == 64


def test_a_patch_that_does_not_fit_is_refused():
    p = fdpv.Patch("x", "f.lvs", "why", (("connect(a, b)\n", "connect(a, c)\n"),), "0" * 64)
    with pytest.raises(DeckError, match="occurs 0 times"):
        fdpv.patched("f.lvs", b"connect(a, d)\n", p)
    with pytest.raises(DeckError, match="occurs 2 times"):
        fdpv.patched("f.lvs", b"connect(a, b)\nconnect(a, b)\n", p)
    with pytest.raises(DeckError, match="not the pinned"):   # fits, but the result is not the pinned file
        fdpv.patched("f.lvs", b"connect(a, b)\n", p)
    good = replace(p, sha256_after=hashlib.sha256(b"connect(a, c)\n").hexdigest())
    assert fdpv.patched("f.lvs", b"connect(a, b)\n", good) == b"connect(a, c)\n"


@pytest.fixture
def fake_deck(tmp_path, monkeypatch):
    """A two-file 'repository' pinned and patched like the real one, the cache in tmp_path."""
    src = tmp_path / "src"
    (src / "klayout/lvs").mkdir(parents=True)
    files = {"klayout/lvs/a.lvs": b"connect(x, y)\n", "klayout/lvs/b.lvs": b"# b\n"}
    for k, v in files.items():
        (src / k).write_bytes(v)
    here = tmp_path / "pins"
    here.mkdir()
    (here / "files.sha256").write_text("".join(f"{hashlib.sha256(v).hexdigest()}  {k}\n" for k, v in files.items()))
    after = hashlib.sha256(b"connect(x, z)\n").hexdigest()
    (here / "0001-x.toml").write_text('# because\nfile = "klayout/lvs/a.lvs"\nsha256_after = "%s"\n'
                                      '[[change]]\nbefore = "connect(x, y)\\n"\nafter = "connect(x, z)\\n"\n' % after)
    monkeypatch.setattr(fdpv, "HERE", here)
    monkeypatch.setenv("PIXELKIT_DECKS", str(tmp_path / "cache"))
    monkeypatch.delenv("PIXELKIT_FD_PV", raising=False)
    return src


def test_installed_from_a_checkout_patched_and_checked_before_every_run(fake_deck):
    assert "not installed" in fdpv.check()
    root = fdpv.install_from(fake_deck)
    assert (root / "klayout/lvs/a.lvs").read_bytes() == b"connect(x, z)\n"      # the patch applied
    assert fdpv.check() is None
    (root / "klayout/lvs/b.lvs").write_bytes(b"# b changed\n")
    assert "not the pinned file" in fdpv.check()
    with pytest.raises(DeckError, match="b.lvs is not the pinned file"):
        fdpv.deck("klayout/lvs/a.lvs")


def test_a_source_file_that_differs_is_refused_and_nothing_installed(fake_deck):
    (fake_deck / "klayout/lvs/b.lvs").write_bytes(b"# another commit\n")
    with pytest.raises(DeckError, match="b.lvs of the fd_pv source has sha256 .* not the pinned"):
        fdpv.install_from(fake_deck)
    assert not fdpv.install_dir().exists()
    (fake_deck / "klayout/lvs/b.lvs").unlink()
    with pytest.raises(DeckError, match="has no file klayout/lvs/b.lvs"):
        fdpv.install_from(fake_deck)


def test_the_env_var_points_the_kit_at_a_checkout(fake_deck, monkeypatch):
    monkeypatch.setenv("PIXELKIT_FD_PV", str(fake_deck))
    assert fdpv.check() is None and fdpv.deck("klayout/lvs/b.lvs").read_bytes() == b"# b\n"


def test_fetch_without_github_says_so(fake_deck, monkeypatch):
    import urllib.request

    def offline(*a, **k):
        raise OSError("Name or service not known")
    monkeypatch.setattr(urllib.request, "urlopen", offline)
    with pytest.raises(DeckError, match="could not download https://codeload.github.com/"):
        fdpv.fetch()


def test_renamed_netlist_renames_models_on_cards_only():
    from pixelkit.layout.signoff.foundry import renamed_netlist
    text = "* pd_c35 in a comment\nDpd vss pd pd_c35 AREA=25p PJ=20u\nMx a b c d nfet_03v3 W=1u L=1u\n"
    out = renamed_netlist(text, (("pd_c35", "diode_nw2ps_03v3"),))
    assert "Dpd vss pd diode_nw2ps_03v3 AREA=25p" in out and out.startswith("* pd_c35 in a comment")


def test_verdict_of_a_signoff_result():
    from pixelkit.layout.flow import verdict
    assert verdict({"lvs": {"match": True}, "drc": {"clean": True}}) == 0
    assert verdict({"lvs": {"match": True}, "foundry_lvs": {"run": False, "reason": "x"}}) == 5
    assert verdict({"lvs": {"match": False}, "foundry_lvs": {"run": False, "reason": "x"}}) == 1
    assert verdict({"density": {"run": True, "clean": False}}) == 1


def test_a_foundry_check_asked_without_its_deck_is_not_run_exit_5(tmp_path, cli, monkeypatch):
    monkeypatch.setenv("PIXELKIT_DECKS", str(tmp_path / "nodecks"))
    monkeypatch.delenv("PIXELKIT_FD_PV", raising=False)
    code, out, err = cli("layout", GF, "--lvs", "--foundry-lvs", "--no-pictures", "--out", tmp_path / "o")
    assert code == 5, err
    assert "LVS (CHIP_2X2, kit extraction" in out and "foundry LVS: NOT RUN - the gf180mcu_fd_pv decks are " \
        "not installed" in out


# ------------------------------------------------------------------- the decks themselves (fd_pv) --

@pytest.fixture(scope="module")
def drawn(tmp_path_factory):
    """Both reference technologies' 2 x 2 chips with their AFEs, as `pixelkit layout` writes them."""
    from pixelkit.design import load_design
    from pixelkit.layout.flow import layout_design
    out = {}
    for path in (GF, REF):
        d = load_design(path)
        folder = tmp_path_factory.mktemp(d.name)
        out[d.name] = (d, folder, layout_design(d, folder, 2, 2, pictures=False, afe=True))
    return out


@pytest.mark.fd_pv
@pytest.mark.parametrize("name", ["dual_pixel_gf180", "dual_pixel_revA"])
def test_foundry_lvs_matches_every_drawn_cell_and_the_chip_in_deep_mode(drawn, name):
    """One deep-mode run on the chip compares every cell of its hierarchy (the pixels, columns, AFEs)
    with its subcircuit of the netlist, labels as drawn: each must be a Match."""
    from pixelkit.layout.signoff.foundry import run_lvs
    d, folder, r = drawn[name]
    top = r["top"]
    res = run_lvs(Path(r["gds"]), top, Path(r["spice"][top]), d.tech, folder / "lvs")
    assert res.match, res.mismatches
    cells = {"PRIMARY", "SECONDARY", "DUALPIX", "COLUMN_P", "COLUMN_S", "AFE_P", "AFE_S", top}
    assert cells <= set(res.circuits) and all(res.circuits[c] == "Match" for c in cells), res.circuits
    assert "Netlists match" in Path(res.log).read_text()


def _variant(cv: Canvas, name: str, edit) -> Canvas:
    out = Canvas(name, cv.rules)
    for s in edit(list(cv.shapes)):
        out.add(s.layer, s.box, s.net)
    for lb in cv.labels:
        out.label(lb.layer, lb.x, lb.y, lb.text)
    return out


@pytest.mark.fd_pv
def test_foundry_lvs_catches_a_missing_contact_a_short_and_a_resized_device(tmp_path):
    """One deep-mode run over the GF180 secondary as drawn and three broken copies, each compared
    with the secondary's netlist: the contacts on FD's diffusion removed (FD open from the SF gate),
    a metal3 bridge between the TG and RST lines, the layout drawn with EC 50 nm wider."""
    from pixelkit.design import load_design
    from pixelkit.layout.library import build_cells
    from pixelkit.layout.signoff.foundry import run_lvs
    from pixelkit.layout.signoff.schematic import circuits_of, lvs_view, spice_text
    d = load_design(GF)
    cells = build_cells(d)
    sec = cells["SECONDARY"]
    dev = d.pixel.devices
    wide = build_cells(replace(d, pixel=replace(d.pixel, devices=replace(dev, ec_w=dev.ec_w + 0.05e-6))))
    lines = sec.ports["lines"]
    y0, y1 = sorted((lines["tg"], lines["rst"]))
    variants = {"GOOD": sec,
                "NOCONTACT": _variant(sec, "NOCONTACT", lambda s: [x for x in s if not (x.layer == "contact"
                                                                                        and x.net == "fd")]),
                "SHORT": _variant(sec, "SHORT", lambda s: s + [Shape("metal3", type(s[0].box)(200, y0, 480, y1), "x")]),
                "RESIZED": _variant(wide["SECONDARY"], "RESIZED", lambda s: s)}
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    top = gdstk.Cell("TOP")
    text = spice_text(lvs_view(d, circuits_of(d, "SECONDARY")), "secondary")
    sub = text[text.index(".subckt"):text.index(".ends")]
    pins = sub.splitlines()[0].split()[2:]
    netlist = ["* variants of the secondary"]
    for k, (name, cv) in enumerate(variants.items()):
        c = cv.to_gdstk(d.tech, {})
        c.name = name
        lib.add(c)
        top.add(gdstk.Reference(c, (k * 20.0, 0)))
        netlist += [sub.replace(".subckt SECONDARY", f".subckt {name}", 1) + f".ends {name}", ""]
    netlist.append(".subckt TOP vss")
    netlist += [f"X{n} " + " ".join(p if p == "vss" else f"{n}_{p}" for p in pins) + f" {n}" for n in variants]
    netlist += [".ends TOP", ".end"]
    lib.add(top)
    gds = tmp_path / "v.gds"
    lib.write_gds(str(gds))
    spice = tmp_path / "v.spice"
    spice.write_text("\n".join(netlist) + "\n")
    res = run_lvs(gds, "TOP", spice, d.tech, tmp_path)
    assert not res.match
    assert res.circuits["GOOD"] == "Match", res.circuits
    for name in ("NOCONTACT", "SHORT", "RESIZED"):
        assert res.circuits[name] == "NoMatch", res.circuits
    said = " | ".join(res.mismatches)
    assert "RESIZED: device EC" in said and "W 0.65 um (layout) vs 0.6 um (netlist)" in said, said
    assert "NOCONTACT: net FD" in said.upper() or "NOCONTACT: device" in said, said
