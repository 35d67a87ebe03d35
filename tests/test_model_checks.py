"""Models checked at load: every device name in every corner, every corner resolvable; when ngspice
fails anyway, its own first error line leads the message and the kept folder is unique and named.

Independent paths: the device names and sections are what the GF180MCU library file itself
defines (grep of the shipped file, not the kit's parser); the ngspice messages are ngspice's
own text for the defect made here (an unclosed parenthesis, a missing section), read from
ngspice's output when the kept deck is run by hand.
"""
import re
import subprocess
from pathlib import Path

import pytest

from conftest import REF, ROOT

TECH = ROOT / "pixelkit" / "tech" / "builtin" / "c35_thesis.toml"


def _tech(tmp_path, edit, folder=None):
    from pixelkit.tech import load_technology
    folder = folder or load_technology("c35_thesis").models.folder
    text = re.sub(r"^folder = .*$", lambda _m: f'folder = "{folder}"', TECH.read_text(), count=1, flags=re.M)
    text = edit(text)
    t = tmp_path / "t.toml"
    t.write_text(text)
    d = tmp_path / "d.toml"
    d.write_text(REF.read_text().replace('"c35_thesis"', f'"{t}"'))
    return d


@pytest.mark.parametrize("edit,key,words", [
    (lambda t: t.replace('nmos = "nfet_03v3"', 'nmos = "nfet_nosuch"'), "mos.nmos", ["nfet_nosuch", "corner 'tt'"]),
    (lambda t: t.replace('pmos = "pfet_03v3"', 'pmos = "PFET_03V3_X"'), "mos.pmos", ["PFET_03V3_X"]),
    (lambda t: re.sub(r"^ss = .*$", "ss = []", t, flags=re.M), "models.corners.ss", ["non-empty"]),
    (lambda t: t.replace('ngspice ff"', 'ngspice ffx"'), "models.corners.ff", ["section ffx not found"]),
    (lambda t: t.replace('kind = "subckt"', 'kind = "model"').replace('nmos = "nfet_03v3"', 'nmos = "nfet_03v3_dss"'),
     "mos.nmos", ["it is a .subckt there"]),
], ids=["unknown_nmos", "unknown_pmos", "empty_corner", "missing_section", "kind_mismatch"])
def test_bad_device_or_corner_is_refused_at_load(tmp_path, cli, edit, key, words):
    code, out, err = cli("models", _tech(tmp_path, edit))
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert f"{key} = " in err and all(w in err for w in words), err


def test_every_shipped_corner_defines_the_devices_as_the_library_file_says(tmp_path):
    """Independent: the names the kit finds agree with a grep of the shipped file."""
    from pixelkit.tech import load_technology
    from pixelkit.tech.libcheck import corner_defines
    tech = load_technology("gf180mcu_3v3")
    lib = (tech.models.folder / "sm141064.ngspice").read_text(errors="replace")
    assert re.search(r"^\.subckt nfet_03v3 ", lib, re.M) and re.search(r"^\.model\s+diode_nw2ps_03v3\s", lib, re.M)
    for corner, includes in tech.models.corners.items():
        found = corner_defines(includes)
        assert found["nfet_03v3"] == "subckt" and found["pfet_03v3"] == "subckt", corner
        assert found["diode_nw2ps_03v3"] == "model", corner


def test_a_model_kind_technology_with_binned_models_loads(tmp_path):
    """mos.kind = "model" naming a binned model (NAME.0, NAME.1 ... as ngspice selects them) is accepted."""
    from pixelkit.design import load_design
    folder = tmp_path / "m"
    folder.mkdir()
    (folder / "b.lib").write_text(".lib tt\n.model nch.0 nmos level=54\n.model nch.1 nmos level=54\n"
                                  ".model pch pmos level=54\n.endl\n")
    d = _tech(tmp_path, lambda t: re.sub(r"\[models\.corners\][\s\S]*", '[models.corners]\ntt = ["lib b.lib tt"]\n',
                                          t.replace('kind = "subckt"', 'kind = "model"')
                                          .replace('nmos = "nfet_03v3"', 'nmos = "nch"')
                                          .replace('pmos = "pfet_03v3"', 'pmos = "pch"')), folder=folder)
    assert load_design(d).tech.mos.nmos == "nch"


def _failing(tmp_path, lib_text, section="sec", title="inj"):
    from pixelkit.spice import Element, Netlist
    from pixelkit.spice.netlist import Op
    from pixelkit.tech.modellib import Include
    folder = tmp_path / "m"
    folder.mkdir(exist_ok=True)
    (folder / "x.lib").write_text(lib_text)
    inc = Include("lib", folder.resolve(), "x.lib", section)
    return Netlist(title, (Element("V1", ("a", "0"), 1.0), Element("R1", ("a", "b"), 1e3),
                           Element("D1", ("b", "0"), "dtiny")), Op(), includes=(inc,))


@pytest.mark.parametrize("lib,section,first", [
    (".lib sec\n.model dtiny d (is=1e-14 bv=((\n.endl\n", "sec", 'Closing ")" not found'),
    (".lib sec\n.endl\n", "nosuch", "section definition nosuch not found"),
], ids=["garbage_card", "missing_section"])
def test_ngspice_first_error_line_leads_the_message(tmp_path, monkeypatch, lib, section, first):
    from pixelkit.errors import SimulationError
    from pixelkit.spice import simulate
    monkeypatch.setenv("PIXELKIT_CACHE", str(tmp_path / "cache"))
    with pytest.raises(SimulationError) as e:
        simulate(_failing(tmp_path, lib, section), use_cache=False)
    msg = e.value.message
    assert first in msg and msg.index(first) < msg.lower().find("fatal error"), msg
    folder = Path(e.value.folder)
    assert folder.parent == tmp_path / "cache" / "failed" and str(folder) in str(e.value)
    # independent: ngspice run by hand on the kept deck prints that line
    out = subprocess.run(["ngspice", "-b", "deck.cir"], cwd=folder, capture_output=True, text=True, timeout=120)
    assert first in out.stdout + out.stderr


def test_kept_failure_folders_are_unique(tmp_path, monkeypatch):
    """The same deck failing with two different model folders: two folders, neither overwritten."""
    from pixelkit.errors import SimulationError
    from pixelkit.spice import simulate
    monkeypatch.setenv("PIXELKIT_CACHE", str(tmp_path / "cache"))
    kept = []
    for k, bad in enumerate(("(", "((")):
        sub = tmp_path / f"f{k}"
        sub.mkdir()
        with pytest.raises(SimulationError) as e:
            simulate(_failing(sub, f".lib sec\n.model dtiny d (is=1e-14 bv={bad}\n.endl\n"), use_cache=False)
        kept.append(Path(e.value.folder))
    assert kept[0] != kept[1] and all(f.is_dir() for f in kept)
    assert (kept[0] / "models").resolve() == (tmp_path / "f0" / "m").resolve()
    assert (kept[1] / "models").resolve() == (tmp_path / "f1" / "m").resolve()
