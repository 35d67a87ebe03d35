"""The virtual camera (issue 11): EMVA 1288 figures of the designed pixel, recovered from its
own exported dataset by independent readers and compared with SPICE-derived values.

Independent paths: the emva1288 reference implementation (its parser, PIL image loading and
its Results1288 fits) and the kit's measured-data reader ``gap.emva`` read the images the
camera drew (Poisson electrons, the pixel's transfer, read noise, mismatch, storage, ADC,
16-bit PNG). What they find is compared with values derived here from SPICE, not from the
camera's model: K by EMVA's definition (the photon-transfer slope over 0 - 70 % of
saturation: var = f'(n)^2 n against mean = f(n)) applied to a SPICE sweep of the pixel's
column signal against the collected charge run here, and the read noise from ngspice's
``.noise`` analysis of the pixel (BSIM4 noise sources, sampled-noise theory) divided by it.
"""
import json
import logging
import warnings

import numpy as np
import pytest

from pixelkit.camera.run import camera
from pixelkit.camera.spicenoise import pixel_noise
from pixelkit.circuits.testbench import dual_pixel_bench, timings
from pixelkit.constants import Q
from pixelkit.spice import simulate_many


@pytest.fixture(scope="module")
def exported(ref_design, tmp_path_factory):
    out = tmp_path_factory.mktemp("emva")
    r = camera(ref_design, seed=3, emva_out=out, shape=(128, 128))
    return r, out


@pytest.fixture(scope="module")
def spice_emva(ref_design, exported):
    """{array: {"standard": (K in DN/e-, sigma_d in e-), "readers": (...)}} an EMVA measurement of
    the SPICE pixel finds, derived here: a sweep of the dual-pixel bench of its own (25 currents from
    dark to the one that takes the PD node through the design swing), var = f'(n)^2 n +
    sigma_read^2 (finite differences; sigma_read from ngspice .noise), K the slope of var - var_dark
    against the mean over 0 - 70 % of saturation (EMVA 1288, through the origin), sigma_d =
    sigma_read / K, all in DN of the camera's ADC. "standard": saturation at the variance
    maximum, as EMVA 1288 and the camera's own figures take it. "readers": saturation as the
    readers find it on a camera's images: the reference implementation scans the variance from
    the brightest exposure down and stops at the first maximum, which on a chip with mismatch is
    the bump where pixels reach the column's clip one after another, so its fit runs to 70 % of
    the clip level (the largest signal of the sweep). The two differ by how much the column
    compresses below its clip: 5.6 % on the secondary at the reference design's 1 uA load,
    4.3 % at the 400 nA of [Thesis2019], so each reader is held to its own definition."""
    from pixelkit.experiments.thesis import _i_max
    d = ref_design
    t_w = d.experiment.t_window
    cur = {w: np.linspace(0.0, _i_max(d, w), 25) for w in ("primary", "secondary")}
    runs = simulate_many([dual_pixel_bench(d, a, b, title=f"emva_ref{k}")
                          for k, (a, b) in enumerate(zip(cur["primary"], cur["secondary"]))])
    tm = timings(d, t_w)
    out = {}
    for which, col in (("primary", "col_p"), ("secondary", "col_s0")):
        lsb = exported[0][which]["figures"]["lsb_V"]
        s = np.array([r.at(col, tm[which].t_reset_level(0)) - r.at(col, tm[which].t_signal(0)) for r in runs])
        s = (s - s[0]) / lsb
        n = cur[which] * t_w / Q
        read = pixel_noise(d, which)["pixel_V"] / lsb
        var = np.gradient(s, n) ** 2 * n + read ** 2
        ks = {}
        for name, top in (("standard", s[int(np.argmax(var))]), ("readers", s.max())):
            lin = s <= 0.7 * top
            ks[name] = float(np.sum(s[lin] * (var[lin] - var[0])) / np.sum(s[lin] ** 2))
        out[which] = {name: (k, read / k) for name, k in ks.items()}
    return out


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
def test_reference_implementation_finds_the_spice_k_and_read_noise(exported, spice_emva, which):
    """Independent reference: SPICE (a sweep of its own, ngspice .noise) through EMVA's
    definitions written here, saturation where the reference implementation finds it
    (``spice_emva``), against emva1288's reading of the images: K within 4 %, sigma_d within
    5 %. Measured on the reference design: K +2.7 / +0.3 %, sigma_d -3.5 / -0.8 % (primary /
    secondary; the thesis's read: +1.9 / +1.2 %, -1.7 / -0.9 %); the remainder is where on the
    noisy 50-step series the reader finds the clip's variance bump. The noise chain the camera
    draws and SPICE's .noise agree to 0.3 %. QE against the camera's own EMVA figure (the same
    definition on its curves). Saturation is not compared: emva1288 takes the first local
    maximum scanning down from the brightest exposure (the clip), the camera (and EMVA 1288) the
    maximum, and the two are 1.8x apart in mu_p.sat."""
    r, out = exported
    want = r[which]["figures"]
    got = _reference_results(out / which)
    k, sigma_d = spice_emva[which]["readers"]
    assert got.K == pytest.approx(k, rel=0.04)
    assert got.sigma_d == pytest.approx(sigma_d, rel=0.05)
    assert got.QE / 100 == pytest.approx(want["qe"], rel=0.05)


@pytest.mark.parametrize("which", ["primary", "secondary"])
def test_gap_emva_finds_the_spice_k_and_read_noise(exported, spice_emva, which):
    """The kit's own EMVA reader (``pixelkit gap emva``, written for measured data) on the
    virtual camera's dataset, against the same SPICE-derived K (4 %) and read noise (5 %): it finds
    saturation as the reference implementation does."""
    from pixelkit.gap.emva import analyse
    r, out = exported
    want = r[which]["figures"]
    nom = analyse(out / which)["nominal"]
    k, sigma_d = spice_emva[which]["readers"]
    assert nom["K_DN_per_e"] == pytest.approx(k, rel=0.04)
    assert nom["sigma_d_measured_e"] == pytest.approx(sigma_d, rel=0.05)
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
    a = camera(ref_design, seed=5, emva_out=tmp_path / "a", steps=6)
    b = camera(ref_design, seed=5, emva_out=tmp_path / "b", steps=6)
    c = camera(ref_design, seed=6, emva_out=tmp_path / "c", steps=6)
    img = "primary/images/b_003_snap_000.png"
    assert (tmp_path / "a" / img).read_bytes() == (tmp_path / "b" / img).read_bytes()
    assert (tmp_path / "a" / img).read_bytes() != (tmp_path / "c" / img).read_bytes()
    assert a["primary"]["figures"] == b["primary"]["figures"]


def test_camera_cli_figures_against_spice(cli, tmp_path, spice_emva, ref_design):
    """Independent references: the SPICE-derived K and sigma_d (above; the command's figures are
    EMVA's definitions on the camera's noiseless curves, so within 1.5 % and 2 %: the camera's
    33-point transfer against the test's 25 points), the output CG of a SPICE charge step (dark
    vs 20000 / 5000 e- double-sampled at the column) against the analytic zero-signal CG_out(0)
    within 3 %, EMVA 1288's SNR_max = sqrt(mu_e,sat) and DR = mu_e.sat / (sigma_d + 1/2), and the
    QE against the technology's QE times the fill factor. (The camera's GSE is the analytic signal
    GSE; it is held against SPICE in test_verify_figures.)"""
    from conftest import REF
    code, out, err = cli("camera", REF, "--json", "--out", tmp_path / "plots")
    assert code == 0, err
    d = json.loads(out)
    for which in ("primary", "secondary"):
        f = d[which]
        k, sigma_d = spice_emva[which]["standard"]
        assert f["k_dn_per_e"] == pytest.approx(k, rel=0.015)
        assert f["read_noise_e"] == pytest.approx(sigma_d, rel=0.02)
        assert f["cg_out_V_per_e"] == pytest.approx(f["cg_out_spice_V_per_e"], rel=0.03)
        assert f["snr_max_db"] == pytest.approx(10 * np.log10(f["saturation_e"]), rel=1e-9)
        # EMVA 1288's definitions: DR = mu_p.sat / mu_p.min with mu_p.min = (sigma_d + 1/2) / eta and
        # mu_e.sat = eta mu_p.sat, so DR = mu_e.sat / (sigma_d + 1/2); QE eta = R / K against the pixel's
        # true QE per pixel area, the technology's QE at 550 nm times photoactive area / pitch^2: EMVA's
        # estimator reads 8.8 / 8.1 % high on a pixel whose column compresses (both slopes over 0 - 70 %
        # of saturation, measured), held to [1.0, 1.12]
        assert f["dr_db"] == pytest.approx(20 * np.log10(f["saturation_e"] / (f["read_noise_e"] + 0.5)), rel=1e-9)
        sub = getattr(ref_design, which)
        eta = float(ref_design.tech.qe(550e-9)) * sub.photoactive_area / sub.pitch ** 2
        assert 1.0 <= f["qe"] / eta <= 1.12, (which, f["qe"], eta)
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
