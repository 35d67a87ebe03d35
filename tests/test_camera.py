"""The virtual camera (issue 11): EMVA 1288 figures of the designed pixel, recovered from its
own exported dataset by an independent reader.

Independent paths: the emva1288 reference implementation (its parser, PIL image loading and
its Results1288 fits) and the kit's measured-data reader ``gap.emva`` read the images the camera drew (Poisson electrons, C(V) response,
read noise, mismatch, storage, ADC, 16-bit PNG) and must find the figures that EMVA's
definitions give on the analytic mean/variance curves (``camera.ptc.analytic``).
"""
import json
import logging
import warnings

import numpy as np
import pytest

from pixelkit.camera.run import camera

SWINGS = {"primary": 0.85, "secondary": 0.845}   # column swings of the reference design (README)


@pytest.fixture(scope="module")
def exported(ref_design, tmp_path_factory):
    out = tmp_path_factory.mktemp("emva")
    r = camera(ref_design, seed=3, swings=SWINGS, emva_out=out, shape=(128, 128))
    return r, out


def _reference_results(folder):
    """emva1288's own pipeline on a descriptor file. The package still calls np.asfarray,
    removed in NumPy 2: the shim restores it for the package only (same semantics)."""
    if not hasattr(np, "asfarray"):
        np.asfarray = lambda a, dtype=float: np.asarray(a, dtype=dtype)
    from emva1288.process import Data1288, LoadImageData, ParseEmvaDescriptorFile, Results1288
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = ParseEmvaDescriptorFile(str(folder / "EMVA1288_Data.txt"), loglevel=logging.ERROR)
        data = Data1288(LoadImageData(p.images, loglevel=logging.ERROR).data)
        return Results1288(data.data, loglevel=logging.ERROR)


@pytest.mark.parametrize("which", ["primary", "secondary"])
def test_reference_implementation_recovers_the_figures(exported, which):
    r, out = exported
    want = r[which]["figures"]
    got = _reference_results(out / which)
    assert got.K == pytest.approx(want["k_dn_per_e"], rel=0.02)
    assert got.sigma_d == pytest.approx(want["read_noise_e"], rel=0.10)
    assert got.QE / 100 == pytest.approx(want["qe"], rel=0.05)
    assert got.u_e_sat == pytest.approx(want["saturation_e"], rel=0.05)


@pytest.mark.parametrize("which", ["primary", "secondary"])
def test_gap_emva_recovers_the_figures(exported, which):
    """The kit's own EMVA reader (``pixelkit gap emva``, written for measured data) on the
    virtual camera's dataset: K within 2 %, read noise within 10 % of the analytic inputs."""
    from pixelkit.gap.emva import analyse
    r, out = exported
    want = r[which]["figures"]
    nom = analyse(out / which)["nominal"]
    assert nom["K_DN_per_e"] == pytest.approx(want["k_dn_per_e"], rel=0.02)
    assert nom["sigma_d_e"] == pytest.approx(want["read_noise_e"], rel=0.10)
    assert nom["eta"] == pytest.approx(want["qe"], rel=0.05)


def test_emva_k_sits_below_the_zero_signal_gain(exported):
    """C(V): the PD and FD capacitances grow as the node discharges, so the PTC slope over
    0 - 70 % of saturation is below q A_sf / C at the reset bias."""
    r, _ = exported
    for which in ("primary", "secondary"):
        f = r[which]["figures"]
        assert 0.8 < f["k_dn_per_e"] / f["k0_dn_per_e"] < 1.0


def test_dataset_layout_matches_the_shared_reference_set(exported):
    _, out = exported
    lines = (out / "primary" / "EMVA1288_Data.txt").read_text().splitlines()
    assert "v 3.0" in lines and "n 12 128 128" in lines
    kinds = [ln.split()[0] for ln in lines if ln and not ln.startswith("#")]
    assert kinds.count("b") == 51 and kinds.count("d") == 51      # 50 pairs + 1 spatial stack each
    assert all((out / "primary" / ln.split()[1]).is_file() for ln in lines if ln.startswith("i "))


def test_same_seed_same_images(ref_design, tmp_path):
    a = camera(ref_design, seed=5, swings=SWINGS, emva_out=tmp_path / "a", steps=6)
    b = camera(ref_design, seed=5, swings=SWINGS, emva_out=tmp_path / "b", steps=6)
    c = camera(ref_design, seed=6, swings=SWINGS, emva_out=tmp_path / "c", steps=6)
    img = "primary/images/b_003_snap_000.png"
    assert (tmp_path / "a" / img).read_bytes() == (tmp_path / "b" / img).read_bytes()
    assert (tmp_path / "a" / img).read_bytes() != (tmp_path / "c" / img).read_bytes()
    assert a["primary"]["figures"] == b["primary"]["figures"]


def test_camera_cli_prints_both_arrays(cli, tmp_path):
    from conftest import REF
    code, out, err = cli("camera", REF, "--json", "--out", tmp_path / "plots")
    assert code == 0, err
    d = json.loads(out)
    for which in ("primary", "secondary"):
        for key in ("k_dn_per_e", "cg_out_V_per_e", "read_noise_e", "qe", "saturation_e", "dr_db",
                    "snr_max_db", "gse"):
            assert np.isfinite(d[which][key])
    assert all((tmp_path / "plots" / f).is_file() for f in ("ptc.png", "snr.png", "noise_breakdown.png"))


def test_camera_cli_rejects_a_bad_size(cli):
    from conftest import REF
    code, _, err = cli("camera", REF, "--size", "12xfoo")
    assert code == 2 and "size" in err and "ROWSxCOLS" in err


def test_camera_refuses_to_overwrite_a_folder_that_is_not_a_dataset(cli, tmp_path):
    """--emva-out DIR writes DIR/primary and DIR/secondary; a non-dataset folder in the way
    is refused before anything is written (the other array's folder is not created)."""
    from conftest import REF
    (tmp_path / "secondary").mkdir()
    (tmp_path / "secondary" / "mine.txt").write_text("keep")
    code, _, err = cli("camera", REF, "--emva-out", tmp_path, "--out", tmp_path / "plots")
    assert code == 2 and "not an EMVA 1288 dataset" in err
    assert not (tmp_path / "primary").exists() and (tmp_path / "secondary" / "mine.txt").read_text() == "keep"
