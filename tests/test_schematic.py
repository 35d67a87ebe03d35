"""Schematics the designer's tools read back: ``pixelkit netlist --schematic`` drawings netlisted by Xschem.

Independent path: Xschem itself (Debian's xschem, installed by setup.sh) reads the drawn ``.sch`` and writes
its SPICE netlist from the drawing's geometry (which wire end touches which pin, which label names which
net); the kit's code only wrote coordinates. Xschem's element lines must be the kit's own, every one, on
the same nets, and the code block the rest of the exported deck in its order. The check can fail: a
drawing with one label renamed gives a netlist that differs (last test).
"""
import shutil
import subprocess
from pathlib import Path

import pytest

from conftest import REF, ROOT

P4T = ROOT / "designs" / "pixel4t_gf180.toml"
NETLIST = ROOT / "designs" / "pixel4t_netlist.toml"


def _library() -> Path:
    """Xschem's own symbol library (devices/lab_pin, iopin, code), beside its binary's share folder."""
    exe = shutil.which("xschem")
    assert exe, "xschem is not on PATH (setup.sh installs it)"
    lib = Path(exe).resolve().parents[1] / "share" / "xschem" / "xschem_library"
    assert (lib / "devices" / "lab_pin.sym").exists(), lib
    return lib


def xschem_netlist(sch: Path, tmp: Path) -> list[str]:
    """Xschem's SPICE netlist of ``sch`` (a copy: Xschem rewrites the file it opens), continuations joined."""
    lines = []
    for ln in xschem_file(sch, tmp).read_text().splitlines():
        if ln.startswith("+") and lines:
            lines[-1] += " " + ln[1:].strip()
        else:
            lines.append(ln)
    return lines


def xschem_file(sch: Path, tmp: Path) -> Path:
    """The SPICE file Xschem writes for ``sch`` (run on a copy of its folder)."""
    work = tmp / f"xs_{sch.stem}"
    shutil.copytree(sch.parent, work, dirs_exist_ok=True)
    out = work / "netlist"
    out.mkdir()
    rc = work / "xschemrc"
    rc.write_text(f"source {_library().parent / 'xschemrc'}\nset netlist_dir {out}\n"
                  f"set XSCHEM_LIBRARY_PATH {_library()}:{work}\n")
    p = subprocess.run(["xschem", "-x", "-q", "-r", "--rcfile", str(rc), "-n", "-s", str(work / sch.name)],
                       cwd=work, capture_output=True, text=True, timeout=120)
    spice = out / f"{sch.stem}.spice"
    assert p.returncode == 0 and spice.exists(), p.stdout[-2000:] + p.stderr[-2000:]
    return spice


def _split(lines):
    """(element lines, code-block lines, the commented .subckt line's ports) of an Xschem netlist."""
    els, code, ports, inside = [], [], None, False
    for ln in lines:
        if "begin user architecture code" in ln:
            inside = True
        elif "end user architecture code" in ln:
            inside = False
        elif ln.startswith("**.subckt"):
            ports = ln.split()[2:]
        elif ln.strip() and not ln.startswith("*") and ln.strip() != ".end":
            (code if inside else els).append(" ".join(ln.split()))
    return els, code, ports


def _norm(text: str) -> str:
    return " ".join(text.split())


@pytest.mark.parametrize("design", [P4T, NETLIST], ids=["generator", "netlist"])
def test_the_pixel_drawn_is_the_pixel_xschem_reads_back(design, cli, tmp_path):
    from pixelkit.family import family_of, load_family_design
    d = load_family_design(design, family_of(design))
    cell = d.cell()
    sub = cell.subckt
    code, _out, err = cli("netlist", design, "--bench", "cell", "--out", tmp_path / "cell.cir",
                          "--schematic", tmp_path / "draw" / "cell.sch", "--json")
    assert code == 0, err
    els, block, ports = _split(xschem_netlist(tmp_path / "draw" / "cell.sch", tmp_path))
    assert sorted(els) == sorted(_norm(e.text()) for e in sub.elements)
    assert ports == list(sub.ports)
    cards = [ln for ln in sub.text().splitlines() if ln.startswith(".model ")] + [m.text() for m in cell.models]
    assert block == [_norm(ln) for ln in cards] and len(block) == 2   # FD's junction models, either way


def test_a_bench_drawn_is_its_deck(cli, tmp_path):
    """The true-CDS bench of the 4T drawn: Xschem's netlist holds the exported deck's lines (elements on the
    same nets; includes, models, the pixel's subcircuit, options, analysis in order), so it runs as the
    deck does (test_pixel4t runs that deck in raw ngspice against the kit)."""
    deck, sch = tmp_path / "cds.cir", tmp_path / "draw" / "cds.sch"
    code, _out, err = cli("netlist", P4T, "--bench", "cds", "--out", deck, "--schematic", sch, "--json")
    assert code == 0, err
    els, block, _ports = _split(xschem_netlist(sch, tmp_path))
    text = [_norm(ln) for ln in deck.read_text().splitlines() if ln.strip() and not ln.startswith("*") and ln != ".end"]
    assert sorted(els + block) == sorted(text)
    assert [ln for ln in text if ln in block] == block   # the code block in the deck's order
    assert len(els) > 30 and any(ln.startswith(".tran") for ln in block)


def test_a_relabelled_drawing_reads_back_as_another_circuit(cli, tmp_path):
    """The check above can fail: one net label of the drawn pixel renamed, Xschem's netlist moves that pin."""
    sch = tmp_path / "draw" / "cell.sch"
    code, _out, err = cli("netlist", P4T, "--bench", "cell", "--out", tmp_path / "cell.cir", "--schematic", sch)
    assert code == 0, err
    good, _b, _p = _split(xschem_netlist(sch, tmp_path))
    text = sch.read_text()
    first = text.index("{devices/lab_pin}")
    label = text[first:text.index("\n", first)]
    sch.write_text(text.replace(label, label.replace("lab=", "lab=moved_"), 1))
    bad, _b, _p = _split(xschem_netlist(sch, tmp_path / "again"))
    assert sorted(bad) != sorted(good)
    assert any("moved_" in ln for ln in bad)


def test_schematic_name_and_reference_bench(cli, tmp_path):
    """A file name that is not .sch is refused (exit 2 naming the option); the reference dual pixel's bench
    draws and reads back too (every element line)."""
    code, _out, err = cli("netlist", P4T, "--out", tmp_path / "x.cir", "--schematic", tmp_path / "x.svg")
    assert code == 2 and "--schematic" in err and ".sch" in err
    deck, sch = tmp_path / "dp.cir", tmp_path / "draw" / "dp.sch"
    code, _out, err = cli("netlist", REF, "--out", deck, "--schematic", sch)
    assert code == 0, err
    els, _block, _ports = _split(xschem_netlist(sch, tmp_path))
    from pixelkit.api import bench
    from pixelkit.design import load_design
    assert sorted(els) == sorted(_norm(e.text()) for e in bench(load_design(REF), "bench_dual_pixel").elements)


def test_xschems_netlist_of_a_drawn_pixel_is_a_netlist_design(tmp_path):
    """The designer's path from Xschem: the 4T netlist file drawn, Xschem's netlist of the drawing (as Xschem
    2.8 writes a top level: ``**.subckt`` ... ``**.ends``) named in a netlist design: the kit reads the same
    pixel - every element line, the ports, the light device - as from the original file."""
    from pixelkit.families.netlist.design import load_netlist_design
    from pixelkit.spice.netlist_in import read_netlist
    from pixelkit.spice.schematic import subckt_schematic
    parsed = read_netlist(NETLIST.parent / "pixel4t_netlist" / "pix4t.spice")
    sch = subckt_schematic(parsed.subckts["pix4t"], tmp_path / "draw" / "pix4t.sch", models=tuple(parsed.models.values()))
    spice = xschem_file(sch, tmp_path)
    assert "**.subckt pix4t" in spice.read_text()
    design = tmp_path / "mine" / "pix4t_xschem.toml"
    design.parent.mkdir()
    shutil.copy(spice, design.parent / "pix4t_from_xschem.spice")
    text = NETLIST.read_text()
    assert 'file = "pixel4t_netlist/pix4t.spice"' in text
    design.write_text(text.replace('file = "pixel4t_netlist/pix4t.spice"', 'file = "pix4t_from_xschem.spice"'))
    a, b = load_netlist_design(NETLIST).cell(), load_netlist_design(design).cell()
    assert a.subckt.ports == b.subckt.ports and a.roles == b.roles
    assert sorted(_norm(e.text()) for e in b.subckt.elements) == sorted(_norm(e.text()) for e in a.subckt.elements)
    assert sorted(m[0] for m in b.subckt.models) == sorted(m[0] for m in a.subckt.models)
