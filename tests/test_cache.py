"""The cache cannot lie: swapped, truncated, bit-flipped and empty entries give the right numbers.

The reference is independent of the cache and of ngspice: an RC charging from a
1 V step reaches 1 - exp(-t / RC) (the derivation), so every number that comes
back - fresh, cached or re-simulated after damage - is checked against it.
"""
import numpy as np
import pytest

from pixelkit.spice import Element, Netlist, Param, Tran, simulate
from pixelkit.spice import cache as cache_mod
from pixelkit.spice import engine
from pixelkit.spice.batch import ngspice_version


@pytest.fixture(autouse=True)
def own_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("PIXELKIT_CACHE", str(tmp_path / "cache"))


def _rc(r: float) -> Netlist:
    return Netlist(f"rc{int(r)}", (Element("V1", ("a", "0"), 1.0), Element("R1", ("a", "b"), r),
                                   Element("C1", ("b", "0"), 1e-9)), Tran(1e-8, 5e-6, 0, 1e-8, uic=True))


def _right(result, r: float) -> bool:
    tau = r * 1e-9
    t = np.array([0.5, 1.0, 1.5]) * tau
    return np.allclose(result.at("b", t), 1 - np.exp(-t / tau), atol=3e-3)


def _entry(net: Netlist):
    return cache_mod.entry_path(engine._key(engine._prepare(net, None), ngspice_version(), "batch"))


def _damage_swap(a, b):
    da, db = a.read_bytes(), b.read_bytes()
    a.write_bytes(db)
    b.write_bytes(da)


def _damage_truncate(a, _b):
    a.write_bytes(a.read_bytes()[: a.stat().st_size // 2])


def _flip_at(frac):
    def damage(a, _b):
        blob = bytearray(a.read_bytes())
        blob[int(len(blob) * frac)] ^= 0x10
        a.write_bytes(bytes(blob))
    return damage


def _damage_empty(a, _b):
    a.write_bytes(b"")


def _damage_copy(a, b):
    a.write_bytes(b.read_bytes())


@pytest.mark.parametrize("damage,said", [
    (_damage_swap, "another key"), (_damage_truncate, "truncated"), (_flip_at(0.05), ""),
    (_flip_at(0.5), ""), (_flip_at(0.9), ""), (_damage_empty, "not a pixelkit cache entry"),
    (_damage_copy, "another key"),
], ids=["swap", "truncate", "flip-head", "flip-middle", "flip-tail", "empty", "copy"])
def test_damaged_entries_give_the_right_numbers(damage, said, capfd):
    a_net, b_net = _rc(1e3), _rc(3e3)
    a, b = simulate(a_net), simulate(b_net)
    assert _right(a, 1e3) and _right(b, 3e3) and not a.meta["cached"]
    damage(_entry(a_net), _entry(b_net))
    capfd.readouterr()
    a2 = simulate(a_net)
    err = capfd.readouterr().err
    assert _right(a2, 1e3)
    assert not a2.meta["cached"], "a damaged entry must be re-simulated, not served"
    assert "cache entry" in err and "re-simulating" in err and said in err
    a3, b3 = simulate(a_net), simulate(b_net)  # the re-simulated entry was stored again
    assert a3.meta["cached"] and _right(a3, 1e3) and _right(b3, 3e3)


def test_an_entry_stores_its_key_and_checksum():
    import hashlib
    import json
    net = _rc(2e3)
    simulate(net)
    blob = _entry(net).read_bytes()
    assert blob.startswith(b"pixelkit-entry 1\n")
    n = int(blob.split(b"\n")[1])
    start = len(b"pixelkit-entry 1\n") + len(b"%d\n" % n)
    header = json.loads(blob[start:start + n])
    assert header["key"] == _entry(net).stem
    (name, size, digest), = header["files"]
    assert hashlib.sha256(blob[-size:]).hexdigest() == digest   # the sum is over the bytes held


def test_retried_run_is_cached_under_its_own_key():
    """abstol < 0 makes the strict run fail (ngspice: timestep too small); the retry's options
    replace it. The loose result is stored under the key of the deck that ran, the strict
    key holds only a redirect, and the result says 'retried' fresh and from the cache."""
    net = _rc(1e3)
    opts = (("abstol", -1.0),)
    r = simulate(net, options=opts)
    assert r.meta["retried"]["options"]["abstol"] == 1e-13 and _right(r, 1e3)
    strict = engine._prepare(net, opts)
    strict_key = engine._key(strict, ngspice_version(), "batch")
    loose_key = engine._key(engine._prepare(strict, r.meta["retried"]["options"]), ngspice_version(), "batch")
    assert loose_key != strict_key and cache_mod.entry_path(loose_key).exists()
    import io
    with np.load(io.BytesIO(cache_mod.STORE.load(strict_key)["result.npz"])) as z:
        assert "__redirect__" in str(z["__meta__"]) and z["__time__"].size == 0
    again = simulate(net, options=opts)
    assert again.meta["cached"] and again.meta["retried"] and _right(again, 1e3)
    assert not simulate(net).meta.get("retried")  # the strict deck of the same circuit is not served it


@pytest.mark.parametrize("backend", ["batch", "shared"])
def test_the_report_counter_sees_every_deck(backend):
    """The report's SPICE counter (an engine observer) counts what was asked of it: three
    different decks run, then the same three served from the cache, on either backend."""
    from pixelkit.spice.counter import SpiceCounter
    nets = [_rc(r) for r in (1e3, 2e3, 3e3)]
    with SpiceCounter(lambda counter: None) as counter:
        first = engine.simulate_many(nets, backend=backend, jobs=2)
        again = engine.simulate_many(nets, backend=backend, jobs=2)
    assert all(_right(res, r) for res, r in zip(first + again, (1e3, 2e3, 3e3) * 2))
    assert (counter.runs, counter.cached, counter.done, counter.total) == (3, 3, 6, 6)
    assert not engine._OBSERVERS  # the observer is gone once the block ends


@pytest.mark.parametrize("edited", ["a.lib", "b.lib"])
def test_an_edited_model_file_is_simulated_again(tmp_path, edited):
    """The key covers every file the library reads (the nested b.lib too), as it is now:
    an edit during the session gives the new numbers, not the cached ones. Reference: the
    RC derivation with the edited resistance."""
    import os
    from pixelkit.tech.modellib import Include
    folder = tmp_path / "models"
    folder.mkdir()
    (folder / "a.lib").write_text(".lib top\n.param rscale=1\n.lib 'b.lib' x\n.endl\n")
    (folder / "b.lib").write_text(".lib x\n.param rr='1000*rscale'\n.endl\n")
    inc = Include("lib", folder.resolve(), "a.lib", "top")

    def net():
        return Netlist("rclib", (Element("V1", ("a", "0"), 1.0), Element("R1", ("a", "b"), Param("rr")),
                                 Element("C1", ("b", "0"), 1e-9)), Tran(1e-8, 5e-6, 0, 1e-8, uic=True),
                       includes=(inc,))
    assert _right(simulate(net()), 1000.0)
    f = folder / edited
    f.write_text(f.read_text().replace("rscale=1", "rscale=2") if edited == "a.lib"
                 else f.read_text().replace("1000*", "2000*"))
    os.utime(f, ns=(f.stat().st_mtime_ns + 10**9,) * 2)
    assert _right(simulate(net()), 2000.0)


def _lib_net(folder):
    from pixelkit.tech.modellib import Include
    inc = Include("lib", folder.resolve(), "a.lib", "top")
    return Netlist("rclib", (Element("V1", ("a", "0"), 1.0), Element("R1", ("a", "b"), Param("rr")),
                             Element("C1", ("b", "0"), 1e-9)), Tran(1e-8, 5e-6, 0, 1e-8, uic=True),
                   includes=(inc,))


def test_two_checkouts_share_entries_and_an_edited_copy_does_not(tmp_path):
    """The key holds the model files' content, not where they lie: the same library in two
    checkouts (copies in two folders) is one cache entry, and an edit of a nested file in one
    copy re-simulates that copy only. Reference: the RC derivation with each copy's resistance."""
    import os
    import shutil
    a = tmp_path / "checkout_a" / "models"
    a.mkdir(parents=True)
    (a / "a.lib").write_text(".lib top\n.param rscale=1\n.lib 'b.lib' x\n.endl\n")
    (a / "b.lib").write_text(".lib x\n.param rr='1000*rscale'\n.endl\n")
    b = tmp_path / "checkout_b" / "models"
    shutil.copytree(a, b)
    first = simulate(_lib_net(a))
    assert _right(first, 1000.0) and not first.meta["cached"]
    other = simulate(_lib_net(b))
    assert other.meta["cached"], "the same model files in another folder must share the entry"
    assert _right(other, 1000.0)
    f = b / "b.lib"
    f.write_text(f.read_text().replace("1000*", "2000*"))
    os.utime(f, ns=(f.stat().st_mtime_ns + 10**9,) * 2)
    edited = simulate(_lib_net(b))
    assert not edited.meta["cached"] and _right(edited, 2000.0)
    again = simulate(_lib_net(a))
    assert again.meta["cached"] and _right(again, 1000.0)


def test_the_shipped_library_copied_elsewhere_keys_the_same(tmp_path):
    """The kit's own model library (the reference designs' GF180 models) copied to another
    folder gives every corner's deck the key it has in place."""
    import dataclasses
    import shutil

    from pathlib import Path

    from pixelkit.design import load_design
    models = load_design(Path(__file__).parents[1] / "designs" / "dual_pixel_revB.toml").tech.models
    copy = tmp_path / "elsewhere"
    shutil.copytree(models.folder, copy)
    for corner in sorted(models.corners):
        incs = models.includes(corner)
        moved = tuple(dataclasses.replace(i, folder=copy.resolve()) for i in incs)
        here = dataclasses.replace(_rc(1e3), includes=incs)
        there = dataclasses.replace(_rc(1e3), includes=moved)
        assert here.text() == there.text()
        assert engine._key(here, "v", "batch") == engine._key(there, "v", "batch")
