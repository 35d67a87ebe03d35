"""The pixel's source follower in moderate inversion: EKV gain and noise against ngspice.

Independent paths: the EKV parameters are fitted (``techfit.ekv``) to the DC source voltages of
ideal-current followers; the checks are ngspice's own small-signal figures of the kit's full
read chain (the SF, the row switch, the mirrored column load): the two-point gain
(``camera.spicenoise.sf_gain``) at biases and levels the fit did not see as derivatives, and the
white noise of ``.noise`` at the column.
"""
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from pixelkit.constants import K_B
from pixelkit.physics import sf
from pixelkit.techfit.ekv import fit, models_for

#: the figures docs/source-follower.md quotes (``sf:KEY`` marks, dotted keys): filled by the tests below from
#: their own runs, read by the page check at the end of the file
MEASURED: dict = {"gain_ekv_minus_spice_pct": {}}
BIASES = [100e-9, 400e-9, 1e-6, 1.6e-6, 4e-6]


def test_ekv_fits_the_model_librarys_follower(ref_design):
    dev = ref_design.pixel.devices
    model, rms = fit(ref_design.tech, dev.sf_w, dev.sf_l, ref_design.temperature)
    assert rms < 5e-3                       # source voltages within a few mV over 50 nA - 4 uA, 1.1 - 2.4 V
    assert 0.3 < model.gamma < 1.2 and 0.4 < model.phi < 1.2


@pytest.mark.parametrize("i_bias", BIASES)
def test_follower_gain_against_spice_over_the_bias_range(ref_design, i_bias):
    """EKV gain vs ngspice's two-point gain of the read chain, 0.1 - 4 uA and FD 1.3 - 2.4 V: within 5 %
    (worst at 4 uA, where the load's output conductance starts to count: docs/source-follower.md's table)."""
    from pixelkit.camera.spicenoise import sf_gain
    d = replace(ref_design, pixel=replace(ref_design.pixel, sf_bias=i_bias))
    row = MEASURED["gain_ekv_minus_spice_pct"].setdefault(f"{i_bias * 1e6:g}uA", {})
    for v_fd in (1.3, 1.7, 2.0, 2.4):
        ekv, spice = sf.follower_gain(d, models_for(d), v_fd), sf_gain(d, v_fd, dv=0.05)
        row[f"{v_fd:g}V"] = 100 * (ekv / spice - 1)
        assert ekv == pytest.approx(spice, rel=0.05), v_fd


def test_the_follower_is_in_moderate_inversion(ref_design):
    """gm / I_D ~ 20 /V and IC ~ 0.8 at 400 nA: neither closed form (weak: 1 / (n U_T) = 31 /V) holds."""
    c = sf.column(ref_design, models_for(ref_design))
    assert 15 < c["gm_over_id_sf"] < 25 and 0.3 < c["ic_sf"] < 3
    assert 1 < c["ic_load"] < 10            # the 1 / 2 um load: moderate to strong


def test_column_white_noise_against_spice(ref_design):
    """ngspice .noise of the read chain at 1 - 5 MHz against the EKV white level (follower, load and its
    mirror, row switch) plus the 1/f model, both low-passed by the column pole: within 10 % (BSIM4's channel
    noise is not EKV's gamma_n; the band and the weak-inversion closed form kT / C_col per sample, below it:
    docs/source-follower.md)."""
    from pixelkit.camera.spicenoise import run_noise, sf_gain
    from pixelkit.circuits.noisebench import read_deck
    from pixelkit.physics.noise import column_capacitance, column_flicker_psd
    c_col = column_capacitance(ref_design)
    ct = sf.column_thermal(ref_design, models_for(ref_design), c_col)
    r = run_noise(read_deck(ref_design, ref_design.pixel.v_pd_reset))
    f_col = 1.0 / (2 * math.pi * ct["z_ohm"] * c_col)
    band = (r["f"] >= 1e6) & (r["f"] <= 5e6)
    model = (ct["white_psd_V2_per_Hz"] + column_flicker_psd(ref_design, sf_gain(ref_design), r["f"][band], models_for(ref_design))) \
        / (1 + (r["f"][band] / f_col) ** 2)
    dev = 100 * (model / r["psd"][band] - 1)
    MEASURED["noise_model_vs_spice_pct_1_5MHz"] = [float(dev.min()), float(dev.max())]
    MEASURED["column_thermal"] = {"variance_V2": ct["variance_V2"], "parts_V2": ct["parts_V2"], "r_rs_ohm": ct["r_rs_ohm"],
                                  "kT_over_C_col_V2": K_B * ref_design.temperature / c_col}
    assert np.all(np.abs(r["psd"][band] / model - 1) < 0.10)


def test_source_follower_page_quotes_the_current_figures(ref_design):
    """docs/source-follower.md quotes the figures measured above (``sf:KEY`` marks: the EKV-minus-SPICE gain
    table, the column noise's parts and its band against ngspice) and the EKV gain against SPICE's at revA's
    own bias and reset level: a change that moves a quoted figure fails here, naming the line
    (``PIXELKIT_DOCS_REWRITE=1`` rewrites them; then read the sentences around them). It reuses the runs of
    the tests above; alone (``-k page``) it repeats them."""
    from docsite import figures
    from pixelkit.camera.spicenoise import sf_gain
    for i in BIASES:
        if f"{i * 1e6:g}uA" not in MEASURED["gain_ekv_minus_spice_pct"]:
            test_follower_gain_against_spice_over_the_bias_range(ref_design, i)
    if "column_thermal" not in MEASURED:
        test_column_white_noise_against_spice(ref_design)
    MEASURED["reset_level_ekv_minus_spice_pct"] = 100 * (
        sf.follower_gain(ref_design, models_for(ref_design), ref_design.pixel.v_pd_reset) / sf_gain(ref_design) - 1)
    page = Path(__file__).resolve().parents[1] / "docs" / "source-follower.md"
    stale = figures.hold([page], "sf", MEASURED)
    assert not stale, "\n".join(stale)
