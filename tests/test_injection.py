"""No user string becomes a second deck line, on either backend; no foreign .spiceinit runs.

Every payload is ``x<SEP>.control<SEP>shell touch <marker><SEP>.endc<SEP>*`` for every
character that some reader (ngspice, PySpice, ``str.splitlines``) treats as a line
break. The check is independent of the kit's own opinion: it is whether the marker
file appears on disk. ``test_marker_detection_works`` shows that the same payload,
handed to ngspice directly, does create the marker (so the test can fail).
"""
import json
import os
import re
import subprocess
import sys

import pytest

from conftest import REF, ROOT
from pixelkit.errors import ConfigError
from pixelkit.spice import Element, Netlist, simulate
from pixelkit.spice.netlist import Model, Op, Param, Subckt, Tran, deck_text

TECH = ROOT / "pixelkit" / "tech" / "builtin" / "c35_thesis.toml"
SEPARATORS = ["\n", "\r", "\r\n", "\v", "\f", "\x1c", "\x1d", "\x1e", "\x85", "\u2028", "\u2029"]
BACKENDS = ["batch", "shared"]
TINY_LIB = ("* a tiny model library (with the technology's two MOS names, which a technology must define)\n"
            ".model dtiny d (is=1e-14)\n.subckt nfet_03v3 d g s b\n.ends\n.subckt pfet_03v3 d g s b\n.ends\n")


def payload(sep: str, marker) -> str:
    return f"x{sep}.control{sep}shell touch {marker}{sep}.endc{sep}*"


def _toml_str(s: str) -> str:
    return json.dumps(s)  # JSON escapes (\uXXXX, \n, \") are valid TOML basic-string escapes


def _builtin_tech_text() -> str:
    """The built-in technology's text with its model folder made absolute (for copies elsewhere)."""
    from pixelkit.tech import load_technology
    folder = load_technology("c35_thesis").models.folder
    return re.sub(r"^folder = .*$", lambda _m: f"folder = {_toml_str(str(folder))}", TECH.read_text(),
                  count=1, flags=re.M)


def _tech_text(folder: str, corners: str = 'tt = ["include tiny.lib"]') -> str:
    """The built-in technology with its model library replaced by ``folder`` and ``corners``."""
    text = re.sub(r"^folder = .*$", lambda _m: f"folder = {_toml_str(folder)}", TECH.read_text(),
                  count=1, flags=re.M)
    head, _, _ = text.partition("[models.corners]")
    return head + "[models.corners]\n" + corners + "\n"


def _diode_deck(tech) -> Netlist:
    return Netlist("inj", (Element("V1", ("a", "0"), 1.0), Element("R1", ("a", "b"), 1e3),
                           Element("D1", ("b", "0"), "dtiny")), Op(), includes=tech.models.includes())


@pytest.mark.parametrize("sep", SEPARATORS, ids=[f"U+{ord(s[-1]):04X}" for s in SEPARATORS])
def test_model_folder_path_never_reaches_a_deck(tmp_path, sep):
    """The hole of issue 9: a model folder whose path holds a separator + .control block.

    The folder exists (so the technology loads), the simulation must run with the
    library from that folder (the diode's operating point proves the include was read),
    on both backends, and the marker must not appear.
    """
    from pixelkit.tech import load_technology
    marker = tmp_path / "pwned"
    folder = tmp_path / f"m{payload(sep, marker)}x"
    folder.mkdir(parents=True)
    (folder / "tiny.lib").write_text(TINY_LIB)
    (tmp_path / "t.toml").write_text(_tech_text(str(folder)))
    tech = load_technology(tmp_path / "t.toml")
    for backend in BACKENDS:
        r = simulate(_diode_deck(tech), backend=backend, use_cache=False)
        assert 0.45 < float(r["v(b)"][0]) < 0.75, backend  # a silicon diode at ~0.4 mA
        assert not marker.exists(), backend


def _design_variants(tmp_path, sep, marker):
    """(label, design text, technology text) with the payload in one string field each."""
    p = _toml_str(payload(sep, marker))
    ref = REF.read_text()
    tech = _builtin_tech_text()
    yield "design.name", ref.replace('name = "dual_pixel_revA"', f"name = {p}"), None
    yield "design.revision", ref.replace('revision = "A"', f"revision = {p}"), None
    yield "design.corner", ref.replace('technology = "c35_thesis"', f'technology = "c35_thesis"\ncorner = {p}'), None
    yield "design.technology", ref.replace('"c35_thesis"', p), None
    yield "afe.opamp", ref.replace('opamp = "macro"', f"opamp = {p}"), None
    yield "spec.note", ref.replace('note = "[Thesis2019]: sensor ~10 mW"', f"note = {p}"), None
    yield "spec.figure", ref.replace("[spec.afe_gain_error]\n", f"[spec.afe_gain_error]\nfigure = {p}\n"), None
    yield "spec.unit", ref.replace("[spec.afe_gain_error]\n", f"[spec.afe_gain_error]\nunit = {p}\n"), None
    yield "spec.name", ref.replace("[spec.afe_gain_error]", f"[spec.{p}]"), None
    yield "spec.limit", ref.replace('max = "0.5 %"', f"max = {p}"), None
    yield "spec.corners", ref.replace("[spec.afe_gain_error]\n", f"[spec.afe_gain_error]\ncorners = [{p}]\n"), None
    yield "verify.corners", ref.replace("[verify]\n", f"[verify]\ncorners = [{p}]\n"), None
    yield "verify.mismatch", ref.replace("[verify]\n", f"[verify]\nmismatch = {p}\n"), None
    for field_, old in [("name", 'name = "c35_thesis"'), ("photodiode.spice_model", 'spice_model = "pd_c35"'),
                        ("mos.nmos", 'nmos = "nfet_03v3"'), ("mos.pmos", 'pmos = "pfet_03v3"'),
                        ("models.default_corner", 'default_corner = "tt"')]:
        key = old.split(" = ")[0]
        yield f"tech.{field_}", None, tech.replace(old, f"{key} = {p}")
    yield "tech.description", None, tech.replace('description = "', f"description = {p[:-1]}")
    yield "tech.corner file", None, tech.replace('"lib sm141064.ngspice typical"',
                                                 _toml_str(f"lib sm{payload(sep, marker)}.ngspice typical"))
    yield "tech.corner section", None, tech.replace('"lib sm141064.ngspice typical"',
                                                    _toml_str(f"lib sm141064.ngspice {payload(sep, marker)}"))
    yield "tech.corner name", None, tech.replace("tt = [", f"{p} = [").replace('default_corner = "tt"',
                                                                            f"default_corner = {p}")
    # issue 44, point 7: the string keys this round added ([close] of issue 40, pixel.gate_drive, the decks)
    knob = '"pixel.sf_bias" = ["600 nA", "1.5 uA"]'
    yield "close.objective", ref + f"\n[close]\nobjective = {p}\n[close.knobs]\n{knob}\n", None
    yield "close.knobs key", ref + f'\n[close]\nobjective = "min power"\n[close.knobs]\n{p} = ["1 V", "2 V"]\n', None
    yield "close.knobs choices", ref + f'\n[close.knobs]\n"pixel.gate_drive" = {{ choices = ["supply", {p}] }}\n', None
    yield "pixel.gate_drive", ref.replace("[pixel]\n", f"[pixel]\ngate_drive = {p}\n"), None
    for key in ("drc_deck", "drc_sha256", "lvs_deck", "lvs_sha256", "pv_decks"):
        signoff = re.sub(rf"^{key} = .*\n", "", tech, flags=re.M)   # the shipped value, if any, replaced
        yield f"tech.signoff.{key}", None, signoff.replace("[signoff]\n", f"[signoff]\n{key} = {p}\n")


@pytest.mark.parametrize("sep", SEPARATORS, ids=[f"U+{ord(s[-1]):04X}" for s in SEPARATORS])
def test_every_design_and_technology_string(tmp_path, sep):
    """Each string field of a design or technology carries the payload: refused at load, or
    (free text that never reaches a deck) the design's deck runs on both backends without
    the marker appearing."""
    from pixelkit.registry import GENERATORS
    from pixelkit.design import load_design
    marker = tmp_path / "pwned"
    ran = []
    for k, (label, design_text, tech_text) in enumerate(_design_variants(tmp_path, sep, marker)):
        d_path = tmp_path / f"d{k}.toml"
        if tech_text is not None:
            (tmp_path / f"t{k}.toml").write_text(tech_text)
            design_text = REF.read_text().replace('"c35_thesis"', _toml_str(str(tmp_path / f"t{k}.toml")))
        d_path.write_text(design_text)
        try:
            design = load_design(d_path)
        except ConfigError:
            continue
        net = GENERATORS["bench_pd_pair"](design)
        for backend in BACKENDS:
            simulate(net, backend=backend, use_cache=False)
        ran.append(label)
    assert not marker.exists()
    assert set(ran) <= {"design.revision", "tech.description", "spec.note"}, ran  # free text only


@pytest.mark.parametrize("sep", SEPARATORS + ["\x00", "\t"], ids=lambda s: f"U+{ord(s[-1]):04X}")
def test_writer_refuses_every_separator(sep):
    """Every string slot of the netlist data types, and the final allowlist on the deck text."""
    bad = payload(sep, "/tmp/x")
    makers = [
        lambda: Netlist(bad, (), Op()),
        lambda: Element(bad, ("a", "0"), 1.0),
        lambda: Element("R1", (bad, "0"), 1.0),
        lambda: Element("X1", ("a", "0"), bad),
        lambda: Element("R1", ("a", "0"), 1.0, ((bad, 1.0),)),
        lambda: Model(bad, "d", ()),
        lambda: Model("m", bad, ()).text(),
        lambda: Model("m", "d", ((bad, 1.0),)).text(),
        lambda: Subckt(bad, ("a",), ()),
        lambda: Subckt("s", (bad,), ()),
        lambda: Subckt("s", ("a",), (), ((bad, 1.0),)).text(),
        lambda: Param(bad),
        lambda: Netlist("t", (), Tran(1e-9, 1e-6), options=(("method", bad),)).text(),
        lambda: Netlist("t", (), Tran(1e-9, 1e-6), options=((bad, 1.0),)).text(),
        lambda: Netlist("t", (), Tran(1e-9, 1e-6), saves=(bad,)).text(),
        lambda: Netlist("t", (), Tran(1e-9, 1e-6), ic=((bad, 1.0),)).text(),
    ]
    if sep != "\n":  # '\n' is the deck's own line break; every other one is refused in the text
        makers.append(lambda: deck_text(f"* ok\n{bad}\n.end\n"))
    for k, make in enumerate(makers):
        with pytest.raises(ConfigError):
            make()
            pytest.fail(f"maker {k} accepted {bad!r}")


_RUN_HERE = """
import sys
from pixelkit.spice import Element, Netlist, Tran, simulate
def main():
    net = Netlist("rc", (Element("V1", ("a", "0"), 1.0), Element("R1", ("a", "b"), 1e3),
                         Element("C1", ("b", "0"), 1e-9)), Tran(1e-8, 1e-6, 0, 1e-8, uic=True))
    r = simulate(net, backend=sys.argv[1], use_cache=False)
    print(float(r["v(b)"][-1]))
if __name__ == "__main__":
    main()
"""


def test_no_user_spiceinit_runs(tmp_path):
    """A .spiceinit in the current folder and in $HOME (ngspice reads both) does not run,
    on either backend; the RC still charges (1 - e^-1 at t = RC)."""
    marker = tmp_path / "pwned"
    init = f"shell touch {marker}\n"
    home = tmp_path / "home"
    home.mkdir()
    (tmp_path / ".spiceinit").write_text(init)
    (home / ".spiceinit").write_text(init)
    (tmp_path / "run.py").write_text(_RUN_HERE)
    env = dict(os.environ, HOME=str(home), PYTHONPATH=str(ROOT))
    for backend in BACKENDS:
        p = subprocess.run([sys.executable, "run.py", backend], cwd=tmp_path, env=env,
                           capture_output=True, text=True, timeout=300)
        assert p.returncode == 0, p.stderr
        assert float(p.stdout.split()[-1]) == pytest.approx(0.632, abs=0.01)
        assert not marker.exists(), backend


def test_marker_detection_works(tmp_path):
    """Positive control: ngspice run directly on a deck with the payload, or with a user
    .spiceinit in its folder, does create the marker - the vector the kit closes is real."""
    m1, m2 = tmp_path / "pwned_deck", tmp_path / "pwned_init"
    (tmp_path / "deck.cir").write_text(f"* title {payload(chr(10), m1)}\nV1 a 0 1\nR1 a 0 1k\n.op\n.end\n")
    (tmp_path / ".spiceinit").write_text(f"shell touch {m2}\n")
    subprocess.run(["ngspice", "-b", "deck.cir"], cwd=tmp_path, capture_output=True, timeout=120,
                   env=dict(os.environ, HOME=str(tmp_path)))
    assert m1.exists() and m2.exists()


@pytest.mark.parametrize("nested", [False, True])
def test_model_library_with_a_control_block_is_refused(tmp_path, nested):
    """A model file is code: one holding a .control block (itself or through an include
    inside the folder) is refused when the technology loads, naming the file."""
    from pixelkit.tech import load_technology
    body = ".model dtiny d (is=1e-14)\n.control\nshell touch /tmp/pwned_by_models\n.endc\n"
    if nested:
        (tmp_path / "inner.lib").write_text(body)
        (tmp_path / "tiny.lib").write_text(".include 'inner.lib'\n")
    else:
        (tmp_path / "tiny.lib").write_text(body)
    (tmp_path / "t.toml").write_text(_tech_text(str(tmp_path)))
    with pytest.raises(ConfigError) as e:
        load_technology(tmp_path / "t.toml")
    assert ".control" in str(e.value) and ("inner.lib" if nested else "tiny.lib") in str(e.value)


def test_model_folder_with_space_and_quote_works(tmp_path):
    """A model folder with a space or a quote in its path works on both backends (the path
    is reached through the kit's link, never written into the deck)."""
    from pixelkit.tech import load_technology
    folder = tmp_path / "my models 'v2' \"final\""
    folder.mkdir()
    (folder / "tiny.lib").write_text(TINY_LIB)
    (tmp_path / "t.toml").write_text(_tech_text(str(folder)))
    tech = load_technology(tmp_path / "t.toml")
    for backend in BACKENDS:
        r = simulate(_diode_deck(tech), backend=backend, use_cache=False)
        assert 0.45 < float(r["v(b)"][0]) < 0.75
