"""Noise and output-referred response of the 5T pixel (issue 11).

Independent paths: ngspice ``.noise`` (BSIM4 channel thermal and flicker noise of the
real devices, the resistor's thermal noise, the devices' own capacitances) with
sampled-noise theory for the read-noise figure; a SPICE transient with a known
photo-charge for the conversion gain. The analytic side is ``physics.noise`` /
``physics.fd`` (closed forms on the kit's C(V) model of the devices).
"""
import numpy as np
import pytest

from pixelkit.camera.spicenoise import ktc_capacitor, output_cg, pixel_noise, run_noise, sf_gain
from pixelkit.circuits.noisebench import flicker_deck, read_deck
from pixelkit.constants import K_B
from pixelkit.physics import fd
from pixelkit.physics.noise import chain, column_flicker_psd, ktc_voltage
from pixelkit.techfit.ekv import models_for


@pytest.fixture(scope="module")
def a_sf(ref_design):
    return sf_gain(ref_design)


@pytest.mark.parametrize("c", [1e-15, 26.5e-15])
def test_ktc_on_a_bare_capacitor_is_kt_over_c(ref_design, c):
    """ngspice integrates the thermal noise of R (4kTR) through the RC: it must give kT/C, any R."""
    for r in (1e3, 1e6):
        assert ktc_capacitor(ref_design, r, c) == pytest.approx(ktc_voltage(c, ref_design.temperature), rel=0.01)


def test_sf_gain_is_below_one_by_the_body_effect(a_sf):
    """Body effect: A_sf ~ 1/(1 + eta), eta = gamma / (2 sqrt(2 phi_F + V_SB)): 0.82 - 0.86 for gamma ~0.58; a 3.3 V NMOS SF lands near."""
    assert 0.7 <= a_sf <= 0.9


@pytest.mark.parametrize("which", ["primary", "secondary"])
def test_read_noise_chain_vs_spice_noise(ref_design, a_sf, which):
    """Analytic NCDS chain (kT/C_FD twice, SF + load kT/C_col) against the SPICE figure:
    ``.noise`` of FD as each switch leaves it (devices' own capacitances, SF Miller) and of
    the read chain weighted by the NCDS filter 2(1 - cos 2 pi f dt) (thermal + 1/f)."""
    an = chain(ref_design, which, a_sf, models_for(ref_design))
    sp = pixel_noise(ref_design, which, a_sf)
    dark_and_leak = an["variance_V2"]["dark_shot"] + an["variance_V2"]["fd_leakage_shot"]
    an_v = np.sqrt(an["pixel_V"] ** 2 - dark_and_leak)
    assert an_v == pytest.approx(sp["pixel_V"], rel=0.10)


def test_signal_sample_keeps_kt_over_cfd_after_charge_sharing(ref_design, a_sf):
    """The derivation in physics/noise.py: after PD and FD share charge through TG, FD holds
    kT/C_total (common mode of the two resets) + kT C_PD/(C_FD C_total) (TG partition) =
    kT/C_FD, the same as a reset sample. SPICE: the transfer sample equals the reset sample."""
    for which in ("primary", "secondary"):
        sp = pixel_noise(ref_design, which, a_sf)
        assert sp["fd_signal_V2"] == pytest.approx(sp["fd_reset_V2"], rel=0.03)
        # and neither is kT/C_total, the naive charge-sharing figure (it would be 5 - 15x smaller)
        c_tot = fd.capacitances(ref_design, which, a_sf)["c_total_F"]
        assert sp["fd_signal_V2"] > 3 * K_B * ref_design.temperature / c_tot


def test_output_cg_vs_spice_charge_step(ref_design, a_sf):
    """CG_out (the transfer, TG's turn-off and RS's turn-on: ``fd.transfer``) against a SPICE transient: the double-sampled
    column signal of a known photo-charge (I x t over the exposure, ~10 % of the swing)
    minus the dark run."""
    spice = output_cg(ref_design)
    for which in ("primary", "secondary"):
        r = fd.response(ref_design, which, a_sf, models_for(ref_design))
        assert r["cg_out_V_per_e"] == pytest.approx(spice[which], rel=0.05)
        # the PD-referred CG of the thesis [Thesis2019] is far from what the column sees
        assert r["cg_pd_V_per_e"] > 1.3 * spice[which]


def test_technology_flicker_coefficient_is_the_model_librarys(ref_design):
    """``mos.kf_vg`` / ``mos.ef`` against ngspice's BSIM4 (fnoimod 1) gate-referred noise of one
    NMOS follower at the fitting point (W/L = 10/1 um, 1 uA): S_vg cox W L f^ef within 3 %, slope ef."""
    mos, w, l = ref_design.tech.mos, 10e-6, 1e-6
    r = run_noise(flicker_deck(ref_design, w, l, 1e-6))
    low = r["f"] <= 100.0
    k = r["psd_in"][low] * mos.cox * w * l * r["f"][low] ** mos.ef
    assert np.median(k) == pytest.approx(mos.kf_vg, rel=0.03)
    slope = np.polyfit(np.log(r["f"][low]), np.log(r["psd_in"][low]), 1)[0]
    assert -slope == pytest.approx(mos.ef, abs=0.03)


def test_column_flicker_spectrum_vs_spice(ref_design, a_sf):
    """The analytic column 1/f PSD (SF through A_sf, load through the follower's output
    conductance, both from the one fitted kf_vg at other sizes and currents: SF 1/0.5 um, load
    1/2 um at 400 nA) against ngspice ``.noise`` of the read chain at 1 - 30 Hz, where 1/f is
    all of it. 20 %: BSIM4's 1/f depends on the bias (kf_vg fitted at 1 uA, 10/1 um). At 400 nA, the
    load the model was checked at; the reference design's 1 uA load reads further below BSIM4's PSD,
    outside the 20 % (docs/noise-camera.md quotes both, held here)."""
    from dataclasses import replace
    d = replace(ref_design, pixel=replace(ref_design.pixel, sf_bias=400e-9))
    r = run_noise(read_deck(d, d.pixel.v_pd_reset))
    low = r["f"] <= 30.0
    ratio = column_flicker_psd(d, sf_gain(d), r["f"][low], models_for(d)) / r["psd"][low]
    assert np.median(ratio) == pytest.approx(1.0, rel=0.20)
    # docs/noise-camera.md and timing-and-settling.md quote it (``nzf:KEY``, % below ngspice): a change that moves it fails here
    import os
    from pathlib import Path
    from docsite import figures
    r1 = run_noise(read_deck(ref_design, ref_design.pixel.v_pd_reset))  # the design's own load, one .noise more
    low1 = r1["f"] <= 30.0
    ratio1 = column_flicker_psd(ref_design, sf_gain(ref_design), r1["f"][low1], models_for(ref_design)) / r1["psd"][low1]
    getters = {"nzf": {"below_400nA": 100 * (1 - float(np.median(ratio))),
                       "below_design": 100 * (1 - float(np.median(ratio1)))}.__getitem__}
    pages = [Path(__file__).resolve().parents[1] / "docs" / p for p in ("noise-camera.md", "timing-and-settling.md")]
    if os.environ.get("PIXELKIT_DOCS_REWRITE"):
        figures.update(None, pages, getters=getters)
    bad, _ = figures.check(None, pages, getters=getters)
    assert not bad, "\n".join(f"{b['page']}:{b['line']}: {b['key']}: quoted {b['quoted']}, now "
                              f"{b.get('now') or b.get('why')}" for b in bad)
