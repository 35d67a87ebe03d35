"""Bad design and technology files end with one clear line and a non-zero exit."""
import re

import pytest

from conftest import REF, ROOT

TECH = ROOT / "pixelkit" / "tech" / "builtin" / "c35_thesis.toml"


def _variant(tmp_path, src, old, new, name="d.toml"):
    text = src.read_text()
    assert re.search(old, text, flags=re.M), old
    path = tmp_path / name
    path.write_text(re.sub(old, lambda _m: new, text, count=1, flags=re.M))
    return path


@pytest.mark.parametrize("old,new,needles", [
    (r'^pd_width = "15.1 um"\n', "", ["primary.pd_width", "missing"]),
    (r'"15.1 um"', '"15.1 pF"', ["primary.pd_width", "'15.1 pF'", "in m"]),
    (r'"15.1 um"', '"-15.1 um"', ["primary.pd_width", "> 0"]),
    (r'"15.1 um"', '15.1', ["primary.pd_width", "with a unit"]),
    (r'"0.64 um2"', '"30 um2"', ["secondary.mask_opening", "no larger than the PD area"]),
    (r'"c35_thesis"', '"c99_magic"', ["technology", "c99_magic", "c35_thesis"]),
    (r'^rows = 27', 'rows = 27.5', ["primary.rows", "whole number"]),
    (r'^opamp = "macro"', 'opamp = "ideal"', ["afe.opamp", "macro, ota"]),
    (r'^name = "dual_pixel_revA"', 'name = "x\\n.control\\nshell rm -rf /\\n.endc"', ["name", "letters, digits"]),
    (r'^\[afe\]', '[afe]\ncolour = "red"', ["afe.colour", "no such field"]),
    (r'"1 ms"', '"1 ms', ["valid TOML"]),
])
def test_bad_design(tmp_path, cli, old, new, needles):
    path = _variant(tmp_path, REF, old, new)
    code, out, err = cli("models", path)
    assert code == 2 and out == ""
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    for n in needles:
        assert n in err, (n, err)


@pytest.mark.parametrize("old,new,needles", [
    (r'^mj = 0.33979\n', "", ["photodiode.mj", "missing"]),
    (r'"7.171877e-5 F/m2"', '"7.171877e-5 F/m"', ["photodiode.cj", "F/m2"]),
    (r'^folder = .*$', 'folder = "/nonexistent/models"', ["models.folder", "existing folder"]),
    (r'"lib sm141064.ngspice typical"', '"lib sm141064.ngspice typical; shell"', ["models.corners.tt"]),
    (r'^qe_curve = \[\[350, 0.05\]', 'qe_curve = [[350, 1.5]', ["qe_curve", "between 0 and 1"]),
])
def test_bad_technology(tmp_path, cli, old, new, needles):
    tech = _variant(tmp_path, TECH, old, new, "tech.toml")
    if "folder" not in old:  # the copy lives elsewhere: its model folder, made absolute
        from pixelkit.tech import load_technology
        folder = load_technology("c35_thesis").models.folder
        tech.write_text(re.sub(r"^folder = .*$", lambda _m: f'folder = "{folder}"', tech.read_text(),
                               count=1, flags=re.M))
    design = _variant(tmp_path, REF, r'"c35_thesis"', f'"{tech}"')
    code, out, err = cli("models", design)
    assert code == 2 and out == "", err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    for n in needles:
        assert n in err, (n, err)


def test_missing_design_file(cli):
    code, out, err = cli("models", "designs/nope.toml")
    assert code == 2 and "Traceback" not in err and "nope.toml" in err


def test_user_technology_file_works(tmp_path, cli):
    from pixelkit.tech import load_technology
    tech = _variant(tmp_path, TECH, r'^name = "c35_thesis"', 'name = "my_c35"', "tech.toml")
    folder = load_technology("c35_thesis").models.folder
    tech.write_text(re.sub(r"^folder = .*$", lambda _m: f'folder = "{folder}"', tech.read_text(), count=1,
                           flags=re.M))
    design = _variant(tmp_path, REF, r'"c35_thesis"', f'"{tech}"')
    code, out, err = cli("models", design)
    assert code == 0, err


# ---- issue 44: the internal errors (exit 3) found on main, each now exit 2 naming field / file ----

def test_npy_scene_whose_header_declares_more_than_the_file_holds(tmp_path, cli):
    """A ``.npy`` header declaring 100000 x 100000 made numpy allocate 74.5 GiB (MemoryError, exit 3):
    the header is checked against the file before anything is allocated; an honest map still loads."""
    import io
    import json

    import numpy as np
    from numpy.lib import format as npf
    buf = io.BytesIO()
    npf.write_array_header_1_0(buf, {"descr": "<f8", "fortran_order": False, "shape": (100000, 100000)})
    big = tmp_path / "big.npy"
    big.write_bytes(buf.getvalue() + b"\0" * 64)
    code, out, err = cli("array", REF, "--rows", "2", "--cols", "2", "--scene", big, "--out", tmp_path / "a", "--json")
    assert code == 2, err
    e = json.loads(out)
    assert e["field"] == "scene" and "100000, 100000" in e["value"] and str(big) in e["error"], e
    from pixelkit.chip.scene import load_map
    np.save(tmp_path / "ok.npy", np.arange(12.0).reshape(3, 4))
    assert load_map(tmp_path / "ok.npy")[0].shape == (3, 4)


def test_a_forged_cache_entry_cannot_declare_a_huge_array(tmp_path, monkeypatch, capsys):
    """A simulation-cache entry is checksummed, but anyone who can write the cache can compute the
    checksum: an entry whose array header declares 10^10 values is refused (said, re-simulated),
    never allocated."""
    import io
    import zipfile

    from numpy.lib import format as npf
    monkeypatch.setenv("PIXELKIT_CACHE", str(tmp_path))
    from pixelkit.spice import cache
    head = io.BytesIO()
    npf.write_array_header_1_0(head, {"descr": "<f8", "fortran_order": False, "shape": (10 ** 10,)})
    z = io.BytesIO()
    with zipfile.ZipFile(z, "w") as zf:
        zf.writestr("__time__.npy", head.getvalue() + b"\0" * 8)
    cache.STORE.save("f" * 64, {cache._NPZ: z.getvalue()})
    assert cache.load("f" * 64) is None
    assert "declares shape (10000000000,) of float64" in capsys.readouterr().err   # refused, not tried


@pytest.mark.parametrize("layer", ["nwell", "active", "poly", "nplus", "metal1", "metal2", "metal3", "metal4"])
def test_a_technology_missing_a_space_rule_names_it(tmp_path, layer):
    """``rules.metal1.space`` absent gave a TypeError in the generators (exit 3; 8 such rules here,
    two more with --afe): every spacing a generator computes with is the technology's error
    naming the key. In process, drawing the 1 x 1 chip with its AFE (what needs every rule)."""
    from dataclasses import replace

    from pixelkit.design import load_design
    from pixelkit.errors import ConfigError
    from pixelkit.layout.library import build_chip_cells
    from pixelkit.tech import load_technology
    raw = (ROOT / "pixelkit" / "tech" / "builtin" / "gf180mcu_3v3.toml").read_text()
    raw = raw.replace('folder = "../models/gf180mcu"', f'folder = "{ROOT / "pixelkit/tech/models/gf180mcu"}"')
    table = raw.index(f"[rules.{layer}]")
    line = re.compile(r"^space = .*\n", flags=re.M).search(raw, table)
    (tmp_path / "t.toml").write_text(raw[:line.start()] + raw[line.end():])
    d = load_design(ROOT / "designs" / "dual_pixel_gf180.toml")
    with pytest.raises(ConfigError) as e:
        build_chip_cells(replace(d, tech=load_technology(tmp_path / "t.toml")), 1, 1, True, "full")
    assert e.value.field == f"rules.{layer}.space", e.value


@pytest.mark.parametrize("kind", ["empty", "random", "truncated", "header-only", "gzip"])
def test_a_bad_layout_gds_is_named(tmp_path, cli, kind):
    """An empty, random, truncated or compressed ``[layout] gds`` (OSError, exit 3 before): exit 2
    naming ``layout.gds`` and the file, before anything runs."""
    import gzip
    import json

    from pixelkit.design import load_design
    from pixelkit.layout.flow import write_gds
    from pixelkit.layout.library import build_library
    good = write_gds(build_library(load_design(REF), 1, 1), tmp_path / "good.gds").read_bytes()
    blob = {"empty": b"", "random": bytes(range(256)) * 8, "truncated": good[:len(good) // 2],
            "header-only": good[:6], "gzip": gzip.compress(good)}[kind]
    (tmp_path / "bad.gds").write_bytes(blob)
    design = tmp_path / "d.toml"
    design.write_text(REF.read_text() + '\n[layout]\ngds = "bad.gds"\n')
    code, out, err = cli("models", design, "--json")
    assert code == 2, err
    e = json.loads(out)
    assert e["field"] == "layout.gds" and "bad.gds" in e["error"] and "GDSII" in e["allowed"], e
