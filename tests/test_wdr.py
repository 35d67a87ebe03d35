"""WDR pixel [Zhou2017]: SPICE circuit vs the decoder and the closed-form model.

Independent paths: the truth is the photocurrent each pixel's current source
carries in the transistor-level deck; the decoder only sees the stored voltages
(C1, C2, V(int)); the knee and the DR come from the charge model derived in
``families/wdr/model.py``; the coding waveforms are checked against the paper's
description (flips at T, 2T, ..., 256T between 1 and 2 V; a ramp of 1/256 V per T).
"""
import json
import math

import numpy as np
import pytest

from conftest import ROOT
from pixelkit.errors import ConfigError
from pixelkit.families.wdr.decode import sample_time
from pixelkit.families.wdr.design import load_wdr_design
from pixelkit.families.wdr.experiment import run_wdr_experiment
from pixelkit.families.wdr.stimulus import signal1_points, signal2_points

DESIGN = ROOT / "designs" / "wdr_pixel.toml"


@pytest.fixture(scope="module")
def design():
    return load_wdr_design(DESIGN)


@pytest.fixture(scope="module")
def result(design):
    return run_wdr_experiment(design)


def test_decoded_intensity_follows_truth_over_five_decades(result):
    """Stated error: 4 % (measured 2.8 %: the node-capacitance estimate and the dark-current model)."""
    assert result["decades"] >= 5.0
    assert result["decode_max_err_frac"] < 0.04
    regimes = {r["regime"] for r in result["sweep"]}
    assert regimes == {"low", "high"}, "the sweep must cover both signal 3 and the comparator"


def test_decoded_flip_time_matches_the_sampling_edge(result):
    """t_c from C1/C2 vs the instant the delayed sampling pulse rose in SPICE (minus t_d)."""
    for r in result["sweep"]:
        if r["regime"] == "high":
            assert r["t_c_decoded_s"] == pytest.approx(r["t_c_spice_s"], rel=0.01)


def test_knee_is_where_v0_puts_it(result):
    """The model's knee (charge model + dark current: the photocurrent that reaches V0 at 2^N T)
    is bracketed by SPICE pixels that did and did not flip, at V0 and at a second V0."""
    k = result["knee"]
    assert k["largest_unflipped_A"] < k["i_knee_model_A"] < k["smallest_flipped_A"]
    assert k["smallest_flipped_A"] / k["largest_unflipped_A"] < 1.4
    alt = result["knee_other_v0"]
    assert alt["v0_V"] == pytest.approx(1.6)
    assert alt["bracket"] == (0.9, 1.1) and alt["flipped"] == [False, True]
    assert alt["i_knee_model_A"] < 0.6 * k["i_knee_model_A"], "a higher V0 acts at less light"


def test_dynamic_range_against_cvdr_plus_steps(result):
    """DR = CVDR + 20 log10(2^N): +48.16 dB for N = 8; the paper expects 112 dB (64 + 48)."""
    assert result["dr_steps_db"] == pytest.approx(20 * math.log10(256), abs=1e-9)
    assert result["dr_db"] == pytest.approx(result["cvdr_db"] + 48.16, abs=1.5)
    assert result["dr_db"] == pytest.approx(112.0, abs=4.0)


def test_coding_waveforms_follow_the_paper():
    t_u = 64e-6
    s1 = np.array(signal1_points(t_u, 8, 1.0, 2.0))
    assert np.allclose(s1[1:, 0] / t_u, [1, 2, 4, 8, 16, 32, 64, 128, 256])
    assert set(np.round(s1[:, 1], 12)) == {1.0, 2.0}
    slopes = np.sign(np.diff(s1[:, 1]))
    assert np.all(slopes[1:] == -slopes[:-1]), "the slope flips at every octave"
    s2 = np.array(signal2_points(t_u, 8, 1.0, 2.0))
    assert (s2[0, 1] - s2[1, 1]) / ((s2[1, 0] - s2[0, 0]) / t_u) == pytest.approx(1 / 256)


def test_decoder_inverts_the_waveforms(design):
    """Sample the PWL waveforms (numpy interpolation) at many times; the decoder returns them."""
    cd = design.coding
    s1 = np.array(signal1_points(cd.t_unit, cd.steps, cd.v_low, cd.v_high))
    s2 = np.array(signal2_points(cd.t_unit, cd.steps, cd.v_low, cd.v_high))
    bounds = cd.t_unit * 2.0 ** np.arange(cd.steps + 1)
    for t in np.geomspace(1.01, 255.0, 97) * cd.t_unit:
        v1, v2 = np.interp(t, *s1.T), np.interp(t, *s2.T)
        assert sample_time(v1, v2, cd) == pytest.approx(t, rel=1e-9)
        # a coarse code off by 0.7 T (the read-in feedthrough) may pick the neighbouring
        # octave only near a boundary, where both candidates are close: error <= 3 x distance
        near = np.min(np.abs(t - bounds))
        for dv in (-0.7, 0.7):
            got = sample_time(v1, v2 + dv * (cd.v_high - cd.v_low) / 256, cd)
            assert abs(got - t) <= 3 * near + 1e-9 * t


def test_bad_design_names_the_field(tmp_path):
    text = DESIGN.read_text().replace('v0 = "1.2 V"', 'v0 = "2.5 V"')
    p = tmp_path / "bad.toml"
    p.write_text(text)
    with pytest.raises(ConfigError, match="pixel.v0"):
        load_wdr_design(p)


def test_cli_simulate_and_models(cli, result):
    code, out, err = cli("simulate", DESIGN, "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["family"] == "wdr" and {"dr_db", "decode_max_err_frac"} <= set(data)
    code, out, err = cli("models", DESIGN, "--json")
    assert code == 0, err
    assert json.loads(out)["dr_formula_db"] > 100


def test_node_dark_current_and_noise_floor_are_derived(result, design):
    """The node's dark current in SPICE (held at each voltage, gmin 1e-18) is its junctions' (physics/dark.py:
    the PD's thermal terms and five switch diffusions) within 10 %; the noise floor the DR rests on is the
    reset and exposure-sample kT/C, the shot noise of SPICE's dark current over the whole 2^N T exposure and
    the readout after the pixel, added in power (within 2 %: the node C at the mean reset level)."""
    from pixelkit.constants import K_B, Q
    from pixelkit.families.wdr.model import dark_current, node_capacitance
    spice = {r["v_V"]: r["i_dark_A"] for r in result["dark_current_vs_voltage"]}
    assert spice[2.0] == pytest.approx(dark_current(design), rel=0.10)
    c, kt = node_capacitance(design, design.pixel.v_reset), K_B * design.temperature
    n_dark = spice[2.0] * 2 ** design.coding.steps * design.coding.t_unit / Q
    v2 = kt / c + kt / design.pixel.c_int + n_dark * (Q / c) ** 2 + design.noise.v_read ** 2
    assert result["v_noise_V"] == pytest.approx(v2 ** 0.5, rel=0.02)


def test_dark_current_page_quotes_the_current_noise_floor(result, design):
    """docs/dark-current.md's noise-floor table and the sentence under it quote the model's parts
    (``wdr:model.KEY``: ``families.wdr.model.noise`` and ``dark_current``), the dark shot noise again from
    SPICE's node current at 2 V (``wdr:spice.KEY``, as the test above derives it) and the simulation's own
    figures (``wdr:sim.KEY``: the experiment's output, as ``pixelkit simulate --json`` prints it): a change
    that moves one fails here, naming the line (``PIXELKIT_DOCS_REWRITE=1`` rewrites them)."""
    from docsite import figures
    from pixelkit.constants import Q
    from pixelkit.families.wdr.model import dark_current, node_capacitance, noise
    n = noise(design)
    model = {**{k[:-1]: v ** 0.5 for k, v in n.items() if k.endswith("_V2")}, "dark_e": n["dark_e"],
             "total_V": n["total_V"], "dark_current_A": dark_current(design)}
    i_spice = {r["v_V"]: r["i_dark_A"] for r in result["dark_current_vs_voltage"]}[2.0]
    n_spice = i_spice * 2 ** design.coding.steps * design.coding.t_unit / Q
    spice = {"dark_e": n_spice, "dark_shot_V": Q * n_spice ** 0.5 / node_capacitance(design, design.pixel.v_reset)}
    figs = {"model": model, "spice": spice, "sim": result}

    stale = figures.hold([ROOT / "docs" / "dark-current.md"], "wdr", figs)
    assert not stale, "\n".join(stale)
