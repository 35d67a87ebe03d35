"""Monte Carlo mismatch: reproducible from the seed, offset FPN against the Pelgrom estimate."""
import numpy as np
import pytest

from pixelkit.mc.montecarlo import run_monte_carlo
from pixelkit.mc.pelgrom import cap_sigma_rel, coefficients, sigma_vth


def test_offset_fpn_matches_pelgrom(ref_design):
    """Independent path: sigma(V_reset,col) = G_SF * A_VT / sqrt(2 Leff Weff) (Pelgrom, with
    the model card's own coefficients and a nominal two-point SF gain), against the spread
    of 96 Monte Carlo pixels (6 x 4 dual pixels, within-column, 80 degrees of freedom).

    Tolerance 0.8 .. 1.3: the sample sigma's own 2-sigma error is +-16 % at 80 dof, and the
    estimate leaves out the RST switch's charge split (at most +8 %, see mc.pelgrom)."""
    r = run_monte_carlo(ref_design, 6, 4, seed=11, jobs=2)
    assert not r["failures"]
    p = r["pelgrom"]
    assert p["dof"] == 80
    assert 0.8 <= p["ratio"] <= 1.3, p
    # double sampling removes most of that offset: the dark signal's spread is far smaller
    for k in ("primary", "secondary"):
        assert r[k]["dsnu_V"] < 0.3 * r[k]["offset_fpn_V"]
        assert 0 < r[k]["prnu_pct"] < 5
    assert r["secondary"]["target_over_dsnu"] > 1


def test_monte_carlo_is_reproducible_from_the_seed(ref_design, tmp_path, monkeypatch):
    """Same seed, fresh cache each time (so ngspice really runs again): identical numbers;
    another seed: other numbers; mismatch off (no seed) gives no spread at all."""
    runs = []
    for k, seed in enumerate((5, 5, 6)):
        monkeypatch.setenv("PIXELKIT_CACHE", str(tmp_path / f"c{k}"))
        runs.append(run_monte_carlo(ref_design, 2, 2, seed=seed, jobs=2))
    a, b, c = runs
    for k in ("primary", "secondary"):
        assert a[k]["dark_signal_V"] == b[k]["dark_signal_V"]
        assert a[k]["reset_level_V"] == b[k]["reset_level_V"]
        assert a[k]["reset_level_V"] != c[k]["reset_level_V"]
    from pixelkit.chip.frame import simulate_frame
    f = simulate_frame(ref_design, np.zeros((2, 2)), np.zeros((2, 6)), jobs=2)
    assert np.ptp(f.reset_level["secondary"], axis=1).max() < 1e-6   # nominal: a row of identical pixels


def test_mismatch_coefficients_from_the_model_card(ref_design):
    """The coefficients are read from the GF180 model file (nfet 7.148 mV um, pfet 6.66 mV um
    as printed in sm141064.ngspice); a W/L = 1/0.5 um device: 0.7071 * 7.148 mV um /
    sqrt(0.35 um * 1.1 um) = 8.15 mV; a 500 fF capacitor at 0.5 %um and 2 fF/um2: 0.0316 %."""
    assert coefficients(ref_design)["par_vth"] == pytest.approx(0.007148)
    assert coefficients(ref_design, "p")["par_vth"] == pytest.approx(0.00666)
    assert sigma_vth(ref_design, 1e-6, 0.5e-6) == pytest.approx(8.15e-3, rel=2e-3)
    assert cap_sigma_rel(ref_design, 500e-15) == pytest.approx(3.162e-4, rel=1e-3)
