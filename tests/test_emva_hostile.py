"""Hostile and degenerate EMVA 1288 folders: one line, exit 2, the file and the reason; nothing decoded
that the descriptor does not allow.

The datasets are written here: a small synthetic camera (16 x 16 pixels, 12 exposure steps; a
linear camera K = 0.5 DN/e-, QE 0.6, Poisson photons, Gaussian read noise, known to the test),
each case one edit of it; and the real reference crop in tests/data for the link cases. The
expectation is the case's own defect (a loop, a pipe, a bomb, identical images ...), stated
before the kit runs; `test_the_clean_synthetic_camera_is_measured` shows the unedited dataset
gives the K and QE it was made with, so each refusal is the edit's doing.
"""
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import ROOT

REAL = ROOT / "tests" / "data" / "emva1288" / "EMVA1288_ReferenceSet_002_CMOS_08Bit"
K, QE = 0.5, 0.6


def make(folder: Path, bits=8, n=12, texp=None, mu_p=None, same=False, zero=False, sat_all=False, seed=1):
    from PIL import Image
    (folder / "img").mkdir(parents=True)
    rng = np.random.default_rng(seed)
    fs = 2 ** bits - 1
    texp = list(texp if texp is not None else np.linspace(1000, 12000, n))
    mu_p = list(mu_p if mu_p is not None else [fs / K / QE * 1.2 * (k + 1) / n for k in range(n)])
    lines = ["v 3.0", f"n {bits} 16 16"]

    def img(mean_e, name):
        if zero:
            a = np.zeros((16, 16))
        elif sat_all and mean_e > 0:
            a = np.full((16, 16), fs)
        else:
            e = rng.poisson(mean_e, (16, 16)) if mean_e > 0 else 0
            a = np.round(8.0 + K * e + rng.normal(0, 2.0, (16, 16)))
        a = np.clip(a, 0, fs).astype(np.uint8)
        if same:
            a[:] = 7
        Image.fromarray(a).save(folder / "img" / name)
        return f"i img/{name}"
    for k, (t, p) in enumerate(zip(texp, mu_p)):
        lines += [f"b {t:.2f} {p:.3f}", img(QE * p, f"b{k}_0.png"), img(QE * p, f"b{k}_1.png"),
                  f"d {t:.2f}", img(0, f"d{k}_0.png"), img(0, f"d{k}_1.png")]
    (folder / "EMVA1288_Data.txt").write_text("\n".join(lines) + "\n")
    return folder


def _edit_descriptor(old, new):
    def edit(f):
        p = f / "EMVA1288_Data.txt"
        p.write_text(p.read_text().replace(old, new, 1))
    return edit


def _replace_image(action):
    def edit(f):
        p = f / "img" / "b3_0.png"
        p.unlink()
        action(p)
    return edit


def _bomb(p):
    from PIL import Image
    Image.new("L", (20000, 20000)).save(p)   # 400 Mpixel of zeros: a 400 kB file


def _huge_file(p):
    with open(p, "wb") as fh:
        fh.truncate(5 << 20)   # far beyond any 16 x 16 8-bit image


def _large_image(p):
    from PIL import Image
    Image.new("L", (4000, 4000)).save(p)     # decodable, but not the stated 16 x 16


def _loop_pair(p):
    other = p.with_name("b3_1.png")
    other.unlink()
    p.symlink_to(other.name)
    other.symlink_to(p.name)


def _drop_darks(f):
    p = f / "EMVA1288_Data.txt"
    p.write_text("\n".join(ln for ln in p.read_text().splitlines()
                           if not ln.startswith("d ") and not ln.startswith("i img/d")) + "\n")


def _sparse_descriptor(f):
    with open(f / "EMVA1288_Data.txt", "wb") as fh:
        fh.truncate(2 << 30)


#: case -> (make() keyword arguments, an edit after it, words the one-line error must hold)
CASES = {
    "self_link": ({}, _replace_image(lambda p: p.symlink_to(p.name)), ["b3_0.png", "loop of symbolic links"]),
    "link_loop": ({}, _replace_image(_loop_pair), ["b3_0.png", "loop of symbolic links"]),
    "fifo_image": ({}, _replace_image(os.mkfifo), ["b3_0.png", "named pipe"]),
    "folder_image": ({}, _replace_image(os.mkdir), ["b3_0.png", "folder"]),
    "dev_zero_image": ({}, _replace_image(lambda p: p.symlink_to("/dev/zero")), ["b3_0.png"]),
    "decompression_bomb": ({}, _replace_image(_bomb), ["b3_0.png", "16 x 16", "not decoded"]),
    "large_image": ({}, _replace_image(_large_image), ["b3_0.png", "4000 x 4000", "not decoded"]),
    "huge_image_file": ({}, _replace_image(_huge_file), ["b3_0.png", "at most"]),
    "sparse_descriptor": ({}, _sparse_descriptor, ["EMVA1288_Data.txt", "at most 4 MiB"]),
    "all_identical": ({"same": True}, None, ["no signal range"]),
    "all_zero": ({"zero": True}, None, ["no signal range"]),
    "all_saturated": ({"sat_all": True}, None, ["every bright step is saturated"]),
    "no_dark_frames": ({}, lambda f: _drop_darks(f), ["no dark steps"]),
    "bits_16_for_8_bit_data": ({}, _edit_descriptor("n 8 16 16", "n 16 16 16"), ["16 bits", "255"]),
    "photons_out_of_order": ({"mu_p": [100.0 * (12 - k) for k in range(12)]}, None,
                             ["photon counts must grow with exposure"]),
    "all_exposures_zero": ({"texp": [0.0] * 12}, None, ["every exposure is 0"]),
    "giant_stated_size": ({}, _edit_descriptor("n 8 16 16", "n 8 100000 100000"), ["at most"]),
    # issue 44: a step listed twice was measured as two (K and the dark current from a copy)
    "one_step_duplicated": ({}, lambda f: _duplicate_step(f, 3), ["repeats the step of line", "each step once"]),
    "image_used_twice": ({}, _edit_descriptor("i img/b4_0.png", "i img/b3_0.png"), ["b3_0.png", "each image once"]),
    "exposures_decreasing": ({"texp": list(np.linspace(12000, 1000, 12)), "mu_p": [100.0 * (k + 1) for k in range(12)]},
                             None, ["increasing light"]),
}


def _duplicate_step(f, k):
    p = f / "EMVA1288_Data.txt"
    lines = p.read_text().splitlines()
    i = [j for j, ln in enumerate(lines) if ln.startswith("b ")][k]
    p.write_text("\n".join(lines[:i + 3] + lines[i:i + 3] + lines[i + 3:]) + "\n")


IN_A_PROCESS = {"fifo_image", "dev_zero_image", "decompression_bomb", "huge_image_file", "sparse_descriptor",
                "giant_stated_size", "large_image"}


def _run(folder, timeout=300):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    p = subprocess.run([sys.executable, "-m", "pixelkit", "gap", "emva", str(folder)], capture_output=True,
                       text=True, timeout=timeout, env=env,
                       preexec_fn=lambda: __import__("resource").setrlimit(__import__("resource").RLIMIT_AS,
                                                                            (3 << 30, 3 << 30)))
    return p.returncode, p.stdout, p.stderr


@pytest.mark.parametrize("case", list(CASES))
def test_hostile_emva_folder(tmp_path, case):
    kw, edit, words = CASES[case]
    folder = make(tmp_path / "ds", **kw)
    if edit:
        edit(folder)
    if case in IN_A_PROCESS:   # could block or eat memory if the check failed: a limited process
        code, out, err = _run(folder)
        assert code == 2, (code, err[-800:])
    else:
        import warnings
        from pixelkit.errors import PixelkitError
        from pixelkit.gap.emva import analyse
        with warnings.catch_warnings():
            warnings.simplefilter("error")   # a numpy warning reaching the user fails the case
            with pytest.raises(PixelkitError) as e:
                analyse(folder)
        assert e.value.exit_status == 2
        err = f"pixelkit: error: {e.value}"
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err and "emva.py" not in err, err
    for w in words:
        assert w in err, (w, err)


def test_the_clean_synthetic_camera_is_measured(tmp_path):
    """The unedited synthetic dataset passes, with the K and QE it was made with."""
    from pixelkit.gap.emva import analyse
    f = analyse(make(tmp_path / "ds"))["figures"]
    assert f["K_DN_per_e"] == pytest.approx(K, rel=0.1) and f["QE_percent"] == pytest.approx(100 * QE, rel=0.1)


@pytest.mark.parametrize("how", ["self", "pair"])
def test_link_loops_in_the_real_dataset(tmp_path, how):
    folder = tmp_path / "real"
    shutil.copytree(REAL, folder)
    pngs = sorted((folder / "images").glob("*.png"))
    a, b = pngs[10], pngs[11]
    a.unlink()
    if how == "self":
        a.symlink_to(a.name)
    else:
        b.unlink()
        a.symlink_to(b.name)
        b.symlink_to(a.name)
    code, out, err = _run(folder)
    assert code == 2 and "loop of symbolic links" in err and a.name in err and len(err.strip().splitlines()) == 1


def test_a_single_exposure_dataset_has_no_dark_current_not_a_nan(tmp_path):
    """Photons varied at one exposure (the irradiance method): the dark current cannot be determined
    (it needs more than two exposures): shown as n/a / null, not refused as a non-finite figure."""
    folder = make(tmp_path / "ds", texp=[5000.0] * 12)
    code, out, err = _run(folder)
    assert code == 0, err
    assert "dark current: n/a e-/s from the mean" in out
