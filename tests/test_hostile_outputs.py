"""Issue 44: output places a user (or someone else) prepared, and a sign-off killed with SIGKILL.

Every case runs the real command and looks at the file system afterwards (independent of the
kit's own messages): the victim file a link points at keeps its bytes, nothing appears where
the kit was refused, and after ``kill -9`` of ``layout --drc`` no KLayout is left and no file
changes (the old kit: KLayout ran on for 6 - 10 s and rewrote the report). The layout is the
GF180 design's 1 x 1 chip without pictures, refused before anything is drawn except where a
case needs the drawing (the kill).
"""
import json
import os
import signal
import subprocess
import sys

import pytest

from conftest import ROOT, run_cli, wait_for

GF = ROOT / "designs" / "dual_pixel_gf180.toml"
LAYOUT = ("layout", GF, "--no-pictures", "--rows", "1", "--cols", "1", "--json")


def _refused(out: str, err: str, path) -> dict:
    e = json.loads(out)
    assert e["exit_status"] == 2 and str(path) in e["error"], e
    assert "internal error" not in err and "Traceback" not in err, err
    return e


@pytest.mark.parametrize("case", ["log-folder", "drc-link", "drc-file", "lvs-file", "out-device", "out-self-link",
                                  "out-fifo"])
def test_layout_refuses_a_prepared_output_place_before_anything_runs(tmp_path, case):
    """A folder where KLayout's log goes (``<out>/drc/CHIP_1X1.drc.log``), ``<out>/drc`` a link to
    another folder, a file named ``drc`` / ``lvs`` (the old kit: an internal error, the ``lvs`` one
    after the whole DRC ran), ``--out /dev/null``, a self-linked ``--out``, a FIFO: exit 2 naming the
    path, before anything is drawn. (A link at a file's name is replaced, never written through:
    ``tests/test_layout.py::test_a_technology_plugs_in_its_own_decks``.)"""
    out, victim = tmp_path / "o", tmp_path / "victim"
    victim.write_text("precious\n")
    opts = ["--drc"]
    if case == "log-folder":
        bad = out / "drc" / "CHIP_1X1.drc.log"
        bad.mkdir(parents=True)
    elif case == "drc-link":
        out.mkdir()
        (tmp_path / "elsewhere").mkdir()
        bad = out / "drc"
        bad.symlink_to(tmp_path / "elsewhere", target_is_directory=True)
    elif case in ("drc-file", "lvs-file"):
        out.mkdir()
        bad = out / case[:3]
        bad.write_text("")
        opts = ["--drc", "--lvs"]
    elif case == "out-device":
        out = bad = "/dev/null"
    elif case == "out-self-link":
        out = bad = tmp_path / "self"
        out.symlink_to(out)
    else:
        out = bad = tmp_path / "fifo"
        os.mkfifo(out)
    code, stdout, err = run_cli(*LAYOUT, *opts, "--out", out)
    assert code == 2, err
    _refused(stdout, err, bad)
    assert victim.read_text() == "precious\n"
    if case in ("log-folder", "drc-link", "drc-file", "lvs-file"):
        assert not (out / "dual_pixel_gf180.gds").exists()   # refused before anything was drawn
        assert not list((tmp_path / "elsewhere").iterdir()) if case == "drc-link" else True
        assert not (out / "drc").is_dir() or case != "lvs-file" or not list((out / "drc").iterdir())


def test_a_folder_the_kit_cannot_write_is_exit_2(tmp_path, monkeypatch):
    """A read-only ``<out>/drc`` (the old kit: PermissionError, exit 3, for a non-root user). The
    test runs as root in CI, where the mode does not stop a write: the refusal the kernel gives a
    user is put at the two calls the kit makes (the check and the temporary file), and each gives
    one line naming the folder."""
    import tempfile

    from pixelkit import fileio
    from pixelkit.errors import PixelkitError
    ro = tmp_path / "o" / "drc"
    ro.mkdir(parents=True)
    ro.chmod(0o555)
    real_access = os.access
    monkeypatch.setattr(fileio.os, "access", lambda p, m, **k: False if str(p) == str(ro) else real_access(p, m, **k))
    with pytest.raises(PixelkitError) as e:
        fileio.write_atomic(ro / "x.lyrdb", "x")
    assert str(ro) in str(e.value) and "not writable" in str(e.value)
    monkeypatch.undo()

    def refuse(*a, **k):
        raise PermissionError(13, "Permission denied")
    monkeypatch.setattr(tempfile, "mkstemp", refuse)
    monkeypatch.setattr(tempfile, "mkdtemp", refuse)
    for write in (lambda: fileio.write_atomic(ro / "x.lyrdb", "x"), lambda: fileio.staging_dir(ro, ".drc.")):
        with pytest.raises(PixelkitError) as e:
            write()
        assert str(ro) in str(e.value) and "Permission denied" in str(e.value)


def test_waveforms_file_needs_an_existing_folder(tmp_path):
    """``--waveforms /nonexistent/dir/w.csv`` made the missing folders (as root, anywhere); a file
    option names a file in a folder that exists: exit 2 before anything is simulated."""
    target = tmp_path / "no" / "such" / "w.csv"
    code, out, err = run_cli("simulate", ROOT / "designs" / "dual_pixel_revA.toml", "--waveforms", target, "--json")
    assert code == 2 and json.loads(out)["field"] == "--waveforms", err
    assert not (tmp_path / "no").exists()


def _klayout_child(pid: int):
    """The pid of the KLayout that ``pid`` runs (setpriv execs it: same pid, its name klayout)."""
    kids = subprocess.run(["pgrep", "-P", str(pid)], capture_output=True, text=True).stdout.split()
    for k in kids:
        try:
            if open(f"/proc/{k}/comm").read().strip() == "klayout":
                return int(k)
        except OSError:
            pass
    return None


def _snapshot(root):
    out = {}
    for dirpath, _, files in os.walk(root):
        for f in files:
            p = os.path.join(dirpath, f)
            st = os.lstat(p)
            out[p] = (st.st_size, st.st_mtime_ns)
    return out


def test_sigkill_of_layout_drc_leaves_no_klayout_and_changes_no_file(tmp_path):
    """kill -9 of ``layout --drc`` while KLayout checks: KLayout goes with it (parent-death signal,
    pixelkit/children.py) and no file under --out changes after the kill - the report is never
    written (the old kit's KLayout ran on and rewrote it). Waits on observable state only: the
    KLayout child with its log growing in the private stage, the pid's end."""
    out = tmp_path / "o"
    env = dict(os.environ, PIXELKIT_PROGRESS="0")
    p = subprocess.Popen([sys.executable, "-m", "pixelkit", *map(str, LAYOUT[:-1]), "--drc", "--out", str(out)],
                         cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         start_new_session=True)
    found = {}

    def checking():
        assert p.poll() is None, p.communicate()[1][-800:]
        found["kl"] = found.get("kl") or _klayout_child(p.pid)
        logs = list((out / "drc").glob(".drc.pk*/CHIP_1X1.drc.log")) if (out / "drc").is_dir() else []
        return found["kl"] and logs and logs[0].stat().st_size > 0
    wait_for(checking, "KLayout checking the chip")
    kl = found["kl"]
    p.send_signal(signal.SIGKILL)
    p.communicate(timeout=600)
    before = _snapshot(out)
    assert not list((out / "drc").glob("*.lyrdb")) and not list((out / "drc").glob(".drc.pk*/*.lyrdb"))

    def gone():
        try:
            return "zombie" in open(f"/proc/{kl}/status").read() or open(f"/proc/{kl}/comm").read().strip() != "klayout"
        except OSError:
            return True
    wait_for(gone, f"KLayout (pid {kl}) to end with its parent", within=120)
    assert _snapshot(out) == before
    assert not list(out.rglob("*.lyrdb"))
    # the next run sweeps the killed run's stage (its owner is gone)
    from pixelkit import owner
    assert owner.sweep(out / "drc", ".drc.") and not list((out / "drc").glob(".drc.*"))
