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
