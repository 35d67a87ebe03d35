"""AFE-probe noise (issue 11): kT/C of C12/C13 and the op-amp's thermal and 1/f noise.

Independent path: ngspice ``.noise`` of the kit's AFE cell at its two phase operating
points (real CMOS switches with BSIM4 channel noise and capacitances, the op-amp
macromodel's noise resistor and 1/f generator), combined by sampled-noise theory
(``camera.afe_spicenoise``), against the closed forms derived in
``physics/afe_noise.py``. The closed forms assume switches fast against the op-amp;
the SPICE switches are not, so 10 %. The former formula (2kT/C11 + kT/C12 +
kT C13/C11^2, 4 kT/C for equal capacitors) fails the noiseless case by 37 %.
"""
from dataclasses import replace

import pytest

from pixelkit.camera.afe_spicenoise import afe_output_noise
from pixelkit.physics.afe_noise import output_variances


def _afe(design, **kw):
    return replace(design, afe=replace(design.afe, **kw))


@pytest.mark.parametrize("change", [
    {},                                   # the reference design: 25 kOhm (20 nV/rtHz), 100 kHz corner
    {"noise_r": 0.0},                     # kT/C of C12 and C13 alone
    {"gbw": 10e6},                        # thermal folding scales with the loop bandwidth
    {"c13": 250e-15},                     # gain 2: beta = 1/3
], ids=["reference", "ktc_only", "gbw_10MHz", "gain_2"])
def test_afe_noise_vs_spice(ref_design, change):
    """Analytic AFE output variance (kT/C + op-amp thermal + 1/f) vs ngspice .noise + sampling, 10 %."""
    d = _afe(ref_design, **change)
    assert sum(output_variances(d).values()) == pytest.approx(afe_output_noise(d)["total_V2"], rel=0.10)


def test_opamp_flicker_through_autozero_vs_spice(ref_design):
    """The 1/f term alone (corner raised to 10 MHz so it is half the total): the analytic
    autozero/CDS weighting |H1 - H2 e^(-j 2 pi f T)|^2 on e_w^2 f_c / f against the
    1/f spectra ngspice gives in the two phase probes, correlated over T = 1/(2 f_clk)."""
    d = _afe(ref_design, noise_corner=10e6)
    sp = afe_output_noise(d)
    an = output_variances(d)["afe_opamp_flicker"]
    assert an == pytest.approx(sp["flicker_V2"], rel=0.10)
    # the autozero removes most of it: two independent samples of the same 1/f noise would add
    assert sp["flicker_V2"] < 0.5 * sp["flicker_uncorrelated_V2"]
