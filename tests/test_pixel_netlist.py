"""A pixel from the designer's SPICE netlist: the shipped 4T netlist (designs/pixel4t_netlist.toml) measured
by the same benches as the 4T generator's pixel, the two equal; a hostile netlist corpus and bad port maps
refused with exit 2 naming what is wrong (through ``pixelkit models``, which reads the netlist and builds the
cell, no simulation)."""
import os
import tomllib
from pathlib import Path

import pytest

from conftest import ROOT
from pixelkit.schema import to_toml

NETLIST_DESIGN = ROOT / "designs" / "pixel4t_netlist.toml"
GOOD_CELL = (ROOT / "designs" / "pixel4t_netlist" / "pix4t.spice").read_text()


def test_the_netlist_path_and_the_generator_measure_the_same_pixel():
    """Same devices, written by the generator or read from the designer's file (another element order,
    the model cards outside the subcircuit, the light added by the light map): the same figures."""
    from pixelkit.family import load_family_design
    from pixelkit.rolepix import suite
    gen = load_family_design(ROOT / "designs" / "pixel4t_gf180.toml", "pixel4t")
    net = load_family_design(NETLIST_DESIGN, "netlist")
    assert gen.cell().subckt.text() != net.cell().subckt.text()
    for group, keys in (("signal", ("cg_V_per_e", "v_sat_V")), ("lag", ("lag_V", "bright_V")), ("noise", ("sigma_V",))):
        a, b = suite.run_group(group, gen), suite.run_group(group, net)
        for k in keys:
            assert b[k] == pytest.approx(a[k], rel=1e-6, abs=1e-9), (group, k)
    figs = suite.figures({"signal": suite.run_group("signal", net), "noise": suite.run_group("noise", net)})
    assert 1 < figs["read_noise"] / 1.602176634e-19 < 3


def _design(tmp_path, cell_text=GOOD_CELL, edit=None, extra=None):
    raw = tomllib.loads(NETLIST_DESIGN.read_text())
    tmp_path.mkdir(parents=True, exist_ok=True)
    (tmp_path / "pix.spice").write_text(cell_text)
    raw["netlist"]["file"] = "pix.spice"
    if edit:
        edit(raw)
    for name, text in (extra or {}).items():
        p = tmp_path / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)
    p = tmp_path / "d.toml"
    p.write_text(to_toml(raw))
    return p


def _refused(cli, design, *words):
    code, out, err = cli("models", design)
    assert code == 2, (code, out, err)
    line = [ln for ln in err.strip().splitlines() if ln.startswith("pixelkit: error")]
    assert len(line) == 1 and "Traceback" not in err, err
    for w in words:
        assert w in line[0], (w, line[0])
    return line[0]


def test_the_shipped_netlist_design_loads(cli):
    code, out, err = cli("models", NETLIST_DESIGN, "--json")
    assert code == 0, err
    assert '"Cppd"' in out and '"pix4t"' in out


SUB = GOOD_CELL.split(".subckt", 1)[1].split(".ends", 1)[0]


@pytest.mark.parametrize("body,words", [
    (".control\nshell touch /tmp/pixelkit_owned\n.endc\n", (".control",)),
    (".subckt pix4t vdd vrst rst tg rs col\n.control\n.endc\n.ends\n", (".control",)),
    (".lib \"/etc/passwd\" tt\n", (".lib",)),
    (".option gmin=1\n", (".option",)),
    (".tran 1n 1u\n", (".tran",)),
    (".temp 100\n", (".temp",)),
    ("R1 a 0 1k\n", ("R1", "subcircuit")),
    (".subckt pix4t vdd vrst rst tg rs col\nQ1 c b e npn\n.ends\n", ("Q1", "element")),
    (".subckt pix4t vdd vrst rst tg rs col\nA1 a b amod\n.ends\n", ("A1",)),
    (".subckt pix4t vdd vrst rst tg rs col\nK1 L1 L2 0.9\n.ends\n", ("K1",)),
    (".subckt pix4t vdd vrst rst tg rs col\nV1 a 0 PWL(0 0 1u 1)\n.ends\n", ("V1", "DC value")),
    (".subckt pix4t vdd vrst rst tg rs col\nB1 a 0 V=system(1)\n.ends\n", ("system",)),
    (".subckt pix4t vdd vrst rst tg rs col\nB1 a 0 V={`touch x`}\n.ends\n", ("B1",)),
    (".subckt pix4t vdd vrst rst tg rs col\nR1 a;b 0 1k\n.ends\n", ()),
    (".subckt pix4t vdd vrst rst tg rs col\nX1 a b nosuch\n.ends\n", ("nosuch",)),
])
def test_hostile_netlists_are_refused(cli, tmp_path, body, words):
    assert not Path("/tmp/pixelkit_owned").exists()
    _refused(cli, _design(tmp_path, body), *words)
    assert not Path("/tmp/pixelkit_owned").exists()


def test_include_loops_escapes_depth_and_size_are_refused(cli, tmp_path):
    # a loop through two files
    loop = _design(tmp_path / "a", ".include \"b.spice\"\n" + GOOD_CELL, extra={"b.spice": ".include \"pix.spice\"\n"})
    _refused(cli, loop, "include loop")
    # out of the design's folder: ../, an absolute path, a link inside pointing out
    _refused(cli, _design(tmp_path / "b", ".include \"../x.spice\"\n" + GOOD_CELL, extra={"../x.spice": "* x\n"}),
             "inside the design's folder")
    _refused(cli, _design(tmp_path / "c", ".include \"/etc/hostname\"\n" + GOOD_CELL), "inside the design's folder")
    (tmp_path / "d").mkdir()
    os.symlink("/etc/hostname", tmp_path / "d" / "link.spice")
    _refused(cli, _design(tmp_path / "d", ".include \"link.spice\"\n" + GOOD_CELL), "inside the design's folder")
    # a chain deeper than the reader goes
    chain = {f"i{k}.spice": f".include \"i{k + 1}.spice\"\n" for k in range(12)}
    chain["i12.spice"] = "* end\n"
    _refused(cli, _design(tmp_path / "e", ".include \"i0.spice\"\n" + GOOD_CELL, extra=chain), "deep")
    # a huge file, a file of zeros, a pipe
    big = _design(tmp_path / "f", GOOD_CELL + ("* " + "x" * 1000 + "\n") * 5000)
    _refused(cli, big, "at most")
    _refused(cli, _design(tmp_path / "g", "\0" * 100 + GOOD_CELL))
    (tmp_path / "h").mkdir()
    os.mkfifo(tmp_path / "h" / "pipe.spice")
    _refused(cli, _design(tmp_path / "h", ".include \"pipe.spice\"\n" + GOOD_CELL), "named pipe")


@pytest.mark.parametrize("edit,words", [
    (lambda r: r["netlist"]["ports"].update(tg="tgx"), ("netlist.ports.tg", "tgx", "a port of pix4t")),
    (lambda r: r["netlist"]["ports"].pop("tg"), ("netlist.ports.tg", "true CDS")),
    (lambda r: r["netlist"]["ports"].pop("vrst"), ("netlist.ports", "vrst", "a role or a")),
    (lambda r: r["netlist"].update(subckt="pixel"), ("netlist.subckt", "pixel")),
    (lambda r: r["netlist"]["probes"].update(fd="nofd"), ("netlist.probes.fd", "nofd")),
    (lambda r: r["netlist"].update(light={"Xsf": {"area": "16 um2"}}), ("netlist.light.Xsf", "a diode")),
    (lambda r: r["netlist"].update(light={"Dnone": {"area": "16 um2"}}), ("netlist.light.Dnone",)),
    (lambda r: r["netlist"].pop("light"), ("netlist.light",)),
    (lambda r: r["netlist"]["ports"].update(sg="tg"), ("netlist.ports.sg", "storage gate")),
])
def test_bad_port_maps_and_light_maps_are_refused_naming_the_field(cli, tmp_path, edit, words):
    _refused(cli, _design(tmp_path, edit=edit), *words)
