"""Every input file the kit reads is bounded: a named pipe, a device, a folder, a file larger
than any real one or a loop of links is refused before it is read (exit 2, one line naming the
file and what was found), never read without limit and never waited on.

Independent check: the kernel. Each run is a real ``pixelkit`` process under an address-space
limit of 2 GiB, given the hostile object through the ordinary option; without the bound,
``/dev/zero`` ends in a MemoryError (exit 3) and a named pipe blocks until the generous
timeout (``test_the_hostile_objects_are_hostile`` shows both happen to a plain reader).

READERS is the one table of inputs: to cover a new input file, add a row (its name, the file
name it must have, and the command line that reads it).
"""
import os
import resource
import subprocess
import sys
import threading

import pytest

from conftest import REF, ROOT

AS_LIMIT = 2 << 30


def _design_with_tech(tmp, tech_path):
    d = tmp / "d.toml"
    d.write_text(REF.read_text().replace('"c35_thesis"', f'"{tech_path}"'))
    return d


def _tech_with_model(tmp, model_name):
    folder = tmp / "models"
    text = (ROOT / "pixelkit" / "tech" / "builtin" / "c35_thesis.toml").read_text()
    head, _, _ = text.partition("[models]")
    t = tmp / "t.toml"
    t.write_text(head + f'[models]\nfolder = "{folder}"\ndefault_corner = "tt"\n[models.corners]\n'
                 f'tt = ["include {model_name}"]\n')
    return _design_with_tech(tmp, t)


#: name -> (file name the hostile object gets inside tmp, command line given tmp and that path)
READERS = {
    "design": ("h.toml", lambda tmp, p: ["models", p]),
    "technology": ("h.toml", lambda tmp, p: ["models", _design_with_tech(tmp, p)]),
    "model_file": ("models/h.lib", lambda tmp, p: ["models", _tech_with_model(tmp, "h.lib")]),
    "measured_csv": ("h.csv", lambda tmp, p: ["gap", "diagnose", REF, "--measured", p]),
    "conditions_csv": ("h.csv", lambda tmp, p: ["gap", "predict", REF, "--conditions", p]),
    "emva_descriptor": ("EMVA1288_Data.txt", lambda tmp, p: ["gap", "emva", tmp]),
    "scene_csv": ("h.csv", lambda tmp, p: ["array", REF, "--scene", p]),
    "scene_npy": ("h.npy", lambda tmp, p: ["array", REF, "--scene", p]),
    "report_baseline": ("summary.json", lambda tmp, p: ["report", REF, "--baseline", tmp, "--out", tmp / "r"]),
    "regress_baseline": ("h.json", lambda tmp, p: ["regress", REF, "--baseline", p]),
    "family_design": ("h.toml", lambda tmp, p: ["simulate", p]),
    # issue 44: the files this round's commands read (waves, signoff) and the design's [layout] gds
    "design_layout_gds": ("h.gds", lambda tmp, p: ["models", _design_with_layout(tmp, p)]),
    "waves_raw": ("h.raw", lambda tmp, p: ["waves", p]),
    "signoff_gds": ("h.gds", lambda tmp, p: ["signoff", p, "--netlist", ROOT / "netlists" / "dual_pixel.cir"]),
    "signoff_netlist": ("h.spice", lambda tmp, p: ["signoff", ROOT / "layouts" / "golden" / "dual_pixel_revA.gds",
                                                   "--top", "DUALPIX_COL", "--netlist", p]),
}


def _design_with_layout(tmp, gds):
    d = tmp / "d.toml"
    d.write_text(REF.read_text() + f'\n[layout]\ngds = "{gds}"\n')
    return d


def _fifo(p):
    os.mkfifo(p)


def _device(p):
    p.symlink_to("/dev/zero")


def _huge(p):
    with open(p, "wb") as fh:   # sparse: no disk used
        fh.truncate(3 << 30)


def _loop(p):
    p.symlink_to(p.name)


def _folder(p):
    p.mkdir()


HOSTILE = {"fifo": _fifo, "dev_zero": _device, "huge_sparse": _huge, "link_loop": _loop, "folder": _folder}
#: what the one-line error must say for each (any one of the words)
SAYS = {"fifo": ("named pipe",), "dev_zero": ("character device", "existing"), "huge_sparse": ("at most", "MiB"),
        "link_loop": ("loop", "existing", "not found"), "folder": ("folder", "directory", "existing")}


def _limited():
    resource.setrlimit(resource.RLIMIT_AS, (AS_LIMIT, AS_LIMIT))


def _run(args, tmp, timeout=300):
    p = subprocess.run([sys.executable, "-m", "pixelkit", *map(str, args)], capture_output=True, text=True,
                       cwd=tmp, timeout=timeout, preexec_fn=_limited,
                       env={**os.environ, "PYTHONPATH": str(ROOT)})
    return p.returncode, p.stdout, p.stderr


CASES = [(r, h) for r in READERS for h in HOSTILE
         # every reader meets the pipe, /dev/zero and the 3 GB file; the design all five
         if h in ("fifo", "dev_zero", "huge_sparse") or r in ("design", "measured_csv", "emva_descriptor")]


@pytest.mark.parametrize("reader,hostile", CASES, ids=[f"{r}-{h}" for r, h in CASES])
def test_hostile_input_refused_before_reading(tmp_path, reader, hostile):
    name, argv = READERS[reader]
    p = tmp_path / name
    p.parent.mkdir(parents=True, exist_ok=True)
    HOSTILE[hostile](p)
    code, out, err = _run(argv(tmp_path, p), tmp_path)
    lines = err.strip().splitlines()
    assert code == 2, (code, err[-500:])
    assert "Traceback" not in err and len(lines) in (1, 4), err   # 4: click's usage error (a folder)
    assert any(w in err for w in SAYS[hostile]), err
    assert str(p.name) in err or str(tmp_path) in err, err


def test_the_hostile_objects_are_hostile(tmp_path):
    """The failure each check prevents: a plain read of /dev/zero under the same address-space
    limit runs out of memory; a plain open of a named pipe blocks (until a writer appears)."""
    code = subprocess.run([sys.executable, "-c", "open('/dev/zero', 'rb').read()"], capture_output=True,
                          preexec_fn=_limited, timeout=300).returncode
    assert code != 0
    fifo = tmp_path / "f"
    os.mkfifo(fifo)
    opened = threading.Event()

    def reader():
        with open(fifo, "rb") as fh:
            opened.set()
            fh.read()
    t = threading.Thread(target=reader, daemon=True)
    t.start()
    assert not opened.wait(0.5)   # still blocked: no writer
    with open(fifo, "wb"):         # release it
        pass
    t.join()
    assert opened.is_set()


def test_bounded_reader_units(tmp_path):
    """The helper itself: a file that grows past the bound while it is read is refused; a file at the
    bound is read; a link is refused where links are not followed."""
    from pixelkit.readfile import FileRefused, read_bytes
    p = tmp_path / "x"
    p.write_bytes(b"a" * 100)
    assert read_bytes(p, "x", "design", limit=100) == b"a" * 100
    with pytest.raises(FileRefused, match="at most 99 bytes"):
        read_bytes(p, "x", "design", limit=99)
    (tmp_path / "l").symlink_to(p)
    assert read_bytes(tmp_path / "l", "x", "design") == b"a" * 100
    with pytest.raises(FileRefused, match="symbolic link"):
        read_bytes(tmp_path / "l", "x", "design", follow=False)
    proc = tmp_path / "proc"
    proc.symlink_to("/proc/self/status")   # states size 0, holds more: read up to the bound only
    with pytest.raises(FileRefused, match="more than 10 bytes"):
        read_bytes(proc, "x", "design", limit=10)
