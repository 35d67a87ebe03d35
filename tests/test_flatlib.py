"""The flattened model-library sections (pixelkit/spice/flatlib.py) against ngspice's own
``.lib`` processing: the same deck run both ways must give bit-identical vectors.

Independent path: ngspice reading the library itself. The comparison fails when a
section is dropped (the deck no longer runs) or a reference is expanded to the
wrong section (checked by hand: nfet_03v3_t -> nfet_03v3_f changes every vector).
"""
import os
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from pixelkit.circuits.array import array_bench
from pixelkit.registry import bench_netlist
from pixelkit.spice import flatlib, scratch
from pixelkit.spice.batch import run_batch
from pixelkit.tech.modellib import Include


def _both_ways(text, links, includes):
    """Vectors of the deck as written and as the runner hands it to ngspice (flattened)."""
    flat_text, flat_links = flatlib.run_deck(text, links, includes, scratch.root())
    assert f'.include "{flatlib.LINK}/' in flat_text and ".lib " not in flat_text
    runs = [run_batch(text, links)[0], run_batch(flat_text, flat_links)[0]]
    for plots in runs:
        assert plots, "a run gave no vectors"
    return runs


def _identical(a, b):
    assert len(a) == len(b)
    for pa, pb in zip(a, b):
        assert pa["data"].keys() == pb["data"].keys()
        for k in pa["data"]:
            assert np.array_equal(np.asarray(pa["data"][k]), np.asarray(pb["data"][k])), k


def _deck_runs(net):
    return _both_ways(net.text(), net.model_links(), net.includes)


@pytest.mark.parametrize("corner", ["tt", "ff", "ss", "fs", "sf"])
def test_gf180_corners_bit_identical(ref_design, corner):
    _identical(*_deck_runs(bench_netlist(replace(ref_design, corner=corner), "bench_dual_pixel")))


def test_afe_and_monte_carlo_decks_bit_identical(ref_design):
    _identical(*_deck_runs(bench_netlist(ref_design, "bench_dual_pixel_afe")))
    # mismatch drawn by the library's own statistical model, after the flattened include
    _identical(*_deck_runs(array_bench(ref_design, [[2e-10]], [[1e-11] * 3], mismatch_seed=3)))


def _lib(tmp_path, files):
    """A model folder: str or bytes file bodies, ("link", target) for a symlink."""
    folder = tmp_path / "lib"
    for name, body in files.items():
        f = folder / name
        f.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(body, tuple):
            f.symlink_to(body[1])
        else:
            f.write_bytes(body if isinstance(body, bytes) else body.encode())
    return folder


def _deck(folder, name, section):
    inc = Include("lib", folder.resolve(), name, section)
    text = f"* t\n{inc.line('models')}\nv1 a 0 'pa*pb'\nr1 a 0 1k\n.op\n.end\n"
    return text, {"models": folder.resolve()}, (inc,)


def _node_a(plots):
    return float(np.real(plots[0]["data"]["v(a)"][0]))


def test_nested_files_resolve_from_the_including_file_and_names_ignore_case(tmp_path):
    # ngspice 39: 'c.lib' inside sub/b.lib is sub/c.lib; section names compare without case;
    # .endl's name is not checked
    folder = _lib(tmp_path, {
        "a.lib": ".LIB Top\n.lib 'sub/b.lib' X\n.param pa=2\n.ENDL other\n",
        "sub/b.lib": "* b\n.lib x\n.lib \"c.lib\" y\n.param pb='pc+1'\n.endl\n",
        "sub/c.lib": ".lib y\n.param pc=5\n.endl\n",
    })
    own, flat = _both_ways(*_deck(folder, "a.lib", "top"))
    assert _node_a(own) == _node_a(flat) == 12.0
    # a nested file edited later in the same process is read again
    c = folder / "sub" / "c.lib"
    c.write_text(".lib y\n.param pc=8\n.endl\n")
    os.utime(c, ns=(c.stat().st_mtime_ns + 10**9,) * 2)
    own, flat = _both_ways(*_deck(folder, "a.lib", "top"))
    assert _node_a(own) == _node_a(flat) == 18.0


def test_empty_section_is_flattened(tmp_path):
    folder = _lib(tmp_path, {"a.lib": ".lib top\n.lib 'a.lib' empty\n.param pa=3 pb=1\n.endl\n"
                                      ".lib empty\n.endl\n"})
    own, flat = _both_ways(*_deck(folder, "a.lib", "top"))
    assert _node_a(own) == _node_a(flat) == pytest.approx(3.0, rel=1e-12)


def test_section_referenced_twice_is_expanded_twice(tmp_path):
    # ngspice expands every reference in place: a device line in it is then a duplicate
    folder = _lib(tmp_path, {"l.lib": ".lib top\n.param pa=1 pb=1\n.lib 'l.lib' m\n.lib 'l.lib' m\n.endl\n"
                                      ".lib m\n.model dd d is=1e-14\nd1 a 0 dd\n.endl\n"})
    text, links, incs = _deck(folder, "l.lib", "top")
    flat_text, flat_links = flatlib.run_deck(text, links, incs, scratch.root())
    body = (scratch.root() / flat_text.split('"')[1]).read_text()
    assert body.count("d1 a 0 dd") == 2
    for t, lk in ((text, links), (flat_text, flat_links)):
        plots, lines, _ = run_batch(t, lk)
        assert not plots and any("d1 a 0 dd" in ln for ln in lines)


@pytest.mark.parametrize("files, why", [
    ({"a.lib": ".lib top\n.include 'p.inc'\n.endl\n", "p.inc": ".param pa=1 pb=1\n"},
     "an include inside a section resolves from another folder"),
    ({"a.lib": ".lib top\n.lib '../outside.lib' x\n.endl\n"}, "a reference leaving the folder"),
    ({"a.lib": ".lib top\n.lib 'a.lib' nosuch\n.endl\n"}, "a missing section"),
    ({"a.lib": ".lib top\n.lib 'a.lib' top\n.endl\n"}, "a reference cycle"),
    ({"a.lib": ".lib top\n.param pa=1 pb=1\n.endl\n.lib top\n.param pa=2 pb=1\n.endl\n"},
     "a section defined twice"),
    ({"a.lib": ".lib top\n.lib 'a.lib' x $ note\n.endl\n.lib x\n.endl\n"}, "a .lib line with more words"),
    ({"a.lib": ".lib top\n.param pa=1 pb=1\n"}, "a section without .endl"),
])
def test_what_is_not_reproduced_exactly_is_left_to_ngspice(tmp_path, files, why):
    text, links, incs = _deck(_lib(tmp_path, files), "a.lib", "top")
    assert flatlib.run_deck(text, links, incs, scratch.root()) == (text, links), why


_B = ".lib x\n.param pa=7\n.endl\n"


@pytest.mark.parametrize("files, flattened", [
    # read as ngspice reads it: flattened, same numbers
    ({"a.lib": b".LIB top\r\n.lib 'b.lib' X\r\n\r\n.param pb=3\r\n.ENDL top\r\n",
      "b.lib": b".Lib x\r\n\t.param pa=7\r\n.endl\r\n"}, True),
    ({"a.lib": "title line\n.lib 'b.lib' x\n.lib top\n.param pb=2\n.lib 'b.lib' x\n.endl\n", "b.lib": _B}, True),
    ({"a.lib": ".lib top\n* tox 41 \u00c5 oxide\n.param pa=7 pb=2 $ \u00c5\n.endl\n"}, True),
    # nested files resolve from the real folder of a linked file (sub/b.lib, not b.lib)
    ({"sub/real.lib": ".lib top\n.param pb=2\n.lib 'b.lib' x\n.endl\n", "sub/b.lib": _B,
      "b.lib": ".lib x\n.param pa=1000\n.endl\n", "a.lib": ("link", "sub/real.lib")}, True),
    # read differently by ngspice, or not reproduced: left to ngspice
    ({"a.lib": ".lib top\n.param pb=3\n.lib 'b.lib' x\n+ pa=100\n.endl\n", "b.lib": _B}, False),
    ({"a.lib": ".include 'defs.inc'\n.lib top\n.param pa=1 pb=1\n.endl\n",
      "defs.inc": ".lib top\n.param pa=9 pb=1\n.endl\n"}, False),
    ({"a.lib": ".lib top\n.lib 'B.lib' x\n.lib 'b.lib' y\n.endl\n", "B.lib": ".lib x\n.param pa=7\n.endl\n",
      "b.lib": ".lib x\n.param pa=1\n.endl\n.lib y\n.param pb=2\n.endl\n"}, False),
    ({"a.lib": ".lib top\n.param pa=2 pb=3\n.endlxyz\n.param pa=5\n.endl\n"}, False),
    ({"a.lib": ".lib top\n.param pb=3\n.library 'b.lib' x\n.endl\n", "b.lib": _B}, False),
    ({"a.lib": b".lib top\n.param pa=7 pb=2 $ note\rpb=9\n.endl\n"}, False),
    ({"a.lib": b".lib top\n.param pb=2\n.lib 'a.lib' \xe4x\n.endl\n.lib \xc4x\n.param pa=7\n.endl\n"}, False),
    ({"a.lib": ".lib top\n.param pb=2\n.lib \"b c.lib\" x\n.endl\n", "b c.lib": _B}, False),
    ({"a.lib": ".lib top $ typical\n.param pa=1 pb=1\n.endl\n.lib TOP\n.param pa=2 pb=1\n.endl\n"}, False),
])
def test_library_quirks_read_as_ngspice_reads_them(tmp_path, files, flattened):
    """Each case from an independent review against ngspice 39: flattened when it can be
    read exactly, left to ngspice otherwise; either way the deck gives ngspice's numbers."""
    text, links, incs = _deck(_lib(tmp_path, files), "a.lib", "top")
    flat_text, flat_links = flatlib.run_deck(text, links, incs, scratch.root())
    assert (flat_text != text) is flattened
    own, flat = run_batch(text, links)[0], run_batch(flat_text, flat_links)[0]
    assert bool(own) == bool(flat)
    if own:
        assert _node_a(own) == _node_a(flat)


def test_no_control_block_reaches_ngspice_through_a_linked_file(tmp_path):
    # the real file's folder holds a harmless x.lib; the link's folder an x.lib with a
    # control block that the kit's scan (which follows real paths, as ngspice) never sees
    marker = tmp_path / "ran"
    folder = _lib(tmp_path, {
        "sub/real.lib": ".lib top\n.param pa=1 pb=1\n.lib 'x.lib' s\n.endl\n",
        "sub/x.lib": ".lib s\n.param q=1\n.endl\n",
        "x.lib": f".lib s\n.control\nshell touch {marker}\n.endc\n.endl\n",
        "a.lib": ("link", "sub/real.lib")})
    text, links, incs = _deck(folder, "a.lib", "top")
    flat_text, flat_links = flatlib.run_deck(text, links, incs, scratch.root())
    assert run_batch(flat_text, flat_links)[0] and not marker.exists()


def test_gf180_diode_sections_bit_identical():
    folder = Path(flatlib.__file__).resolve().parents[1] / "tech" / "models" / "gf180mcu"
    for corner in ("diode_typical", "diode_ss", "diode_ff"):
        incs = (Include("lib", folder, "sm141064.ngspice", "typical"),
                Include("lib", folder, "sm141064.ngspice", corner), Include("include", folder, "design.ngspice", ""))
        text = ("* t\n" + "\n".join(i.line("models") for i in incs) + "\nv1 a 0 dc 0\n"
                "d1 0 a diode_nd2ps_03v3 area=1e-10 pj=4e-5\nd2 0 a diode_pd2nw_03v3 area=1e-10 pj=4e-5\n"
                ".dc v1 -1 0.8 0.01\n.end\n")
        _identical(*_both_ways(text, {"models": folder}, incs))


def test_the_engine_hands_ngspice_the_flattened_deck(ref_design, monkeypatch):
    from pixelkit.spice import engine, simulate
    seen = []
    real = engine.run_batch
    monkeypatch.setattr(engine, "run_batch", lambda text, links: seen.append(text) or real(text, links))
    simulate(bench_netlist(ref_design, "bench_dual_pixel"), use_cache=False)
    assert seen and all(f'.include "{flatlib.LINK}/' in t and ".lib " not in t for t in seen)
