"""One checked store serves both caches: nothing in the cache can lie, hang or pile up.

Independent references: the RC derivation 1 - exp(-t/RC) for simulation results (as in
test_cache.py); for report sections, the same report built with --no-cache (which reads
no cache entry); for debris, the file system after a real SIGKILL. Where a check guards
against a hang (a named pipe in the cache), the reader runs in a thread with a generous
bound and the pipe is released afterwards, so a regression fails instead of hanging.
"""
import json
import os
import signal
import subprocess
import sys
import threading

import pytest

from conftest import REF_QUICK_EXIT, REF, ROOT, wait_for
from pixelkit.spice import simulate
from pixelkit.spice import cache as cache_mod
from pixelkit.spice import engine
from pixelkit.spice.batch import ngspice_version
from test_cache import _rc, _right   # the RC circuit and its derivation


def _entry(net):
    return cache_mod.entry_path(engine._key(engine._prepare(net, None), ngspice_version(), "batch"))


def _in_thread(fn, bound=120.0, release=None):
    """fn() in a thread; fails (instead of hanging) if it has not returned within ``bound`` s."""
    out = {}
    t = threading.Thread(target=lambda: out.setdefault("r", fn()), daemon=True)
    t.start()
    t.join(bound)
    if t.is_alive():
        if release:
            release()
        t.join(30)
        pytest.fail("the cache blocked on what stands in place of an entry")
    return out["r"]


def _fifo(p):
    os.mkfifo(p)


def _folder(p):
    p.mkdir()
    (p / "x").write_text("x")


def _dev_zero(p):
    p.symlink_to("/dev/zero")


def _link_out(p):   # a valid-looking entry outside the cache
    outside = p.parents[3] / "outside.entry"
    outside.write_bytes(b"pixelkit-entry 1\n")
    p.symlink_to(outside)


@pytest.mark.parametrize("make,said", [(_fifo, "named pipe"), (_folder, "folder"), (_dev_zero, "symbolic link"),
                                       (_link_out, "symbolic link")],
                         ids=["fifo", "folder", "dev_zero_link", "link_out_of_cache"])
def test_what_is_not_an_entry_is_refused_unread(tmp_path, monkeypatch, capfd, make, said):
    monkeypatch.setenv("PIXELKIT_CACHE", str(tmp_path / "c" / "cache"))
    net = _rc(1e3)
    assert _right(simulate(net), 1e3)
    p = _entry(net)
    p.unlink()
    make(p)
    capfd.readouterr()

    def release():
        if p.is_fifo():
            with open(p, "wb"):
                pass
    r = _in_thread(lambda: simulate(net), release=release)
    err = capfd.readouterr().err
    assert _right(r, 1e3) and not r.meta["cached"]
    assert f"cache entry {p}" in err and said in err and "re-simulating" in err, err
    assert p.is_file() and not p.is_symlink() and simulate(net).meta["cached"]   # replaced by a real entry
    if make is _link_out:
        assert (tmp_path / "c" / "outside.entry").read_bytes() == b"pixelkit-entry 1\n"   # untouched


def test_a_refused_extraction_entry_is_called_an_extraction_cache_file(tmp_path, monkeypatch, capfd):
    """Issue 44: a refused extraction-cache entry was called a "report-cache file"."""
    monkeypatch.setenv("PIXELKIT_CACHE", str(tmp_path / "cache"))
    from pixelkit.layout.pex.overlay import store
    s = store()
    p = s.path("e" * 64)
    p.parent.mkdir(parents=True)
    p.mkdir()
    assert s.load("e" * 64) is None
    err = capfd.readouterr().err
    assert f"cache entry {p}" in err and "extraction-cache file" in err and "report-cache" not in err, err


def test_a_linked_cache_folder_leading_outside_is_not_used(tmp_path, monkeypatch, capfd):
    monkeypatch.setenv("PIXELKIT_CACHE", str(tmp_path / "cache"))
    net = _rc(2e3)
    simulate(net)
    sub = _entry(net).parent
    elsewhere = tmp_path / "elsewhere"
    sub.rename(elsewhere)
    sub.symlink_to(elsewhere)
    capfd.readouterr()
    r = simulate(net)
    err = capfd.readouterr().err
    assert _right(r, 2e3) and not r.meta["cached"] and "outside the cache" in err


# --- report sections -------------------------------------------------------------------------

@pytest.fixture(scope="module")
def report_env(tmp_path_factory):
    root = tmp_path_factory.mktemp("rc")
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PIXELKIT_CACHE": str(root / "cache"), "PIXELKIT_PROGRESS": "0"}
    shared = os.path.join(os.environ["PIXELKIT_CACHE"], "sim")   # SPICE results shared with the other
    os.makedirs(shared, exist_ok=True)                            # report tests; the report cache is this
    (root / "cache").mkdir()                                      # module's own
    (root / "cache" / "sim").symlink_to(shared)
    ref = root / "ref"   # built with an empty report cache, so it read no entry: the independent reference
    p = subprocess.run([sys.executable, "-m", "pixelkit", "report", REF, "--quick", "--out", ref],
                       capture_output=True, text=True, env=env, cwd=root, timeout=1200)
    assert p.returncode == REF_QUICK_EXIT, p.stderr[-2000:]
    assert json.loads((ref / "summary.json").read_text())["sections_from_cache"] == 0
    return root, env, ref


def _report(root, env, out, *extra):
    return subprocess.run([sys.executable, "-m", "pixelkit", "report", REF, "--quick", "--out", out, *extra],
                          capture_output=True, text=True, env=env, cwd=root, timeout=1200)


def _entries(env):
    return sorted((os.path.join(d, f) for d, _, fs in os.walk(os.path.join(env["PIXELKIT_CACHE"], "report"))
                   for f in fs if f.endswith(".entry")))


def _checked(folder):
    return json.loads((folder / "summary.json").read_text())["checked"]


def _pictures(folder):
    return {p.name: p.read_bytes() for p in folder.glob("*.png")}


def test_report_cache_tampering_is_found(report_env):
    """One byte of a cached section's number and a cached figure cut to 200 bytes: the next
    report says so, rebuilds them, and prints exactly the figures of the uncached reference."""
    root, env, ref = report_env
    number = next(iter(_checked(ref).values()))["value"]
    text = repr(float(number)).encode()
    hit = [e for e in _entries(env) if text in open(e, "rb").read()]
    assert hit, "no cached section holds the checked figure"
    blob = bytearray(open(hit[0], "rb").read())
    i = blob.index(text)
    blob[i] = ord("2") if blob[i] != ord("2") else ord("3")   # 1.10e-09 -> 2.10e-09, as in the issue
    open(hit[0], "wb").write(bytes(blob))
    png = max((e for e in _entries(env) if e != hit[0] and b"\x89PNG" in open(e, "rb").read()),
              key=os.path.getsize)
    data = open(png, "rb").read()
    open(png, "wb").write(data[:data.index(b"\x89PNG") + 200])
    p = _report(root, env, root / "again")
    assert p.returncode == REF_QUICK_EXIT, p.stderr[-2000:]
    assert p.stderr.count("rebuilding the section") == 2, p.stderr
    assert "fails its checksum" in p.stderr and "truncated" in p.stderr
    assert _checked(root / "again") == _checked(ref)
    assert _pictures(root / "again") == _pictures(ref)


def test_a_pipe_in_the_report_cache_does_not_block(report_env):
    root, env, ref = report_env
    e = _entries(env)[0]
    os.unlink(e)
    os.mkfifo(e)
    p = _report(root, env, root / "piped")
    assert p.returncode == REF_QUICK_EXIT and "named pipe" in p.stderr, p.stderr[-2000:]
    assert _checked(root / "piped") == _checked(ref)
    assert os.path.isfile(e) and not os.path.islink(e)


def test_kill_9_of_report_leaves_no_pile(report_env):
    """SIGKILL while the report is being staged, three times: the earlier report stays whole,
    and the next complete run removes every staging folder the killed runs left."""
    root, env, ref = report_env
    out = root / "killed"
    assert _report(root, env, out).returncode == REF_QUICK_EXIT
    before = _checked(out)
    for _ in range(3):
        p = subprocess.Popen([sys.executable, "-m", "pixelkit", "report", REF, "--quick", "--out", str(out)],
                             env=env, cwd=root, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        wait_for(lambda: any(n.startswith(".killed.new-") for n in os.listdir(root)) or p.poll() is not None,
                 "the staging folder")
        p.send_signal(signal.SIGKILL)
        p.wait()
        assert _checked(out) == before
    stale = [n for n in os.listdir(root) if n.startswith(".killed.")]
    assert stale, "the kill came too late to leave debris: the test proves nothing"
    q = _report(root, env, out)
    assert q.returncode == REF_QUICK_EXIT, q.stderr[-2000:]
    assert [n for n in os.listdir(root) if n.startswith(".killed.")] == []
    assert _checked(out) == _checked(ref)


# --- killed in the middle of a save ----------------------------------------------------------

_BLOCK_AT_RENAME = """
import os, sys
import pixelkit.{module} as m
def held(*a, **k):
    print("saving", flush=True)
    sys.stdin.read()
m.os.replace = held
{call}
"""


def _killed_while_saving(env, module, call):
    p = subprocess.Popen([sys.executable, "-c", _BLOCK_AT_RENAME.format(module=module, call=call)], env=env,
                         stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "saving"   # the temporary is written, the rename not done
    p.kill()
    p.wait()


def test_kill_9_during_a_cache_save_is_cleaned_by_the_next_run(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PIXELKIT_CACHE": str(tmp_path / "cache")}
    _killed_while_saving(env, "cachestore", "m.Store('sim', 'sim-cache', 'x').save('ab' * 32, "
                                            "{'result.npz': b'x' * 655000})")
    tmp = tmp_path / "cache" / "sim" / "tmp"
    assert [f.stat().st_size > 655000 for f in tmp.iterdir()] == [True]   # the killed run's temporary
    p = subprocess.run([sys.executable, "-m", "pixelkit", "simulate", REF, "--json"], capture_output=True,
                       text=True, env=env, cwd=tmp_path, timeout=1200)
    assert p.returncode == 0, p.stderr[-2000:]
    assert list(tmp.iterdir()) == []


def test_kill_9_during_an_output_write_is_cleaned_by_the_next_write(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    target = tmp_path / "out.csv"
    _killed_while_saving(env, "fileio", f"m.write_atomic({str(target)!r}, 'a' * 1000)")
    assert [p.name.startswith(".out.csv.pk") for p in tmp_path.iterdir()] == [True]
    from pixelkit.fileio import write_atomic
    write_atomic(target, "b")
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]


def test_a_live_owners_temporary_is_left_alone(tmp_path):
    """The sweep removes only what belongs to a process that is gone (this one is alive)."""
    from pixelkit import owner
    mine = tmp_path / f".x.{owner.tag()}.abc"
    mine.write_text("in progress")
    dead = tmp_path / ".x.pk999999999-1.abc"   # no such process
    dead.write_text("debris")
    assert owner.sweep(tmp_path, ".x.") == [dead] and mine.exists()



def test_a_copied_checkout_keys_report_sections_alike_and_an_edit_does_not(tmp_path):
    """Issue 41: a report section's key holds the content of the design, the kit and the model files,
    not where the checkout lies: two copies of the kit (every path in them different) give a section
    the same key, so the sections one copy built serve the other; an edited model file (not kit code:
    only the model files' fingerprint sees it) or an edited design file gives another key."""
    import shutil
    code = ("import sys; from pixelkit.design import load_design; from pixelkit.report.cache import section_key; "
            "print(section_key('signoff', load_design(sys.argv[1]), {'quick': False}))")

    def key(root, design="designs/dual_pixel_revB.toml"):
        p = subprocess.run([sys.executable, "-c", code, str(design)], cwd=root, capture_output=True, text=True, timeout=120,
                           env={**os.environ, "PYTHONPATH": str(root)})
        assert p.returncode == 0, p.stderr[-2000:]
        return p.stdout.strip()
    roots = [tmp_path / name / "kit" for name in ("a", "elsewhere_b")]
    for r in roots:
        shutil.copytree(os.path.join(ROOT, "pixelkit"), r / "pixelkit", ignore=shutil.ignore_patterns("__pycache__"))
        (r / "designs").mkdir()
        shutil.copy(os.path.join(ROOT, "designs", "dual_pixel_revB.toml"), r / "designs")
    first = key(roots[0])
    assert key(roots[1]) == first, "the same content in another folder must key the section alike"
    assert key(roots[1], roots[1] / "designs" / "dual_pixel_revB.toml") == first, "an absolute path keys alike"
    model = roots[1] / "pixelkit" / "tech" / "models" / "gf180mcu" / "design.ngspice"
    model.write_text(model.read_text() + "\n* edited\n")
    edited_model = key(roots[1])
    design = roots[0] / "designs" / "dual_pixel_revB.toml"
    design.write_text(design.read_text() + "\n# edited\n")
    assert len({first, edited_model, key(roots[0])}) == 3
