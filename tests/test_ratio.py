"""Ratio pixel [Sun2016]: the SPICE loop and PWM readout vs the derived law.

Independent paths: the loop's photocurrents are the current sources of the
transistor-level deck (GF180 nfet_03v3 in weak inversion); the interval law
T/tau = R_F - 1/R_F is derived in ``families/ratio/law.py`` and checked against
the inverter trip times with tau taken from the uniform (1:1) pair alone; the
resolution numbers come from the paper (1.62, 25.6 dB) and from the golden
ratio (1 + sqrt 5)/2, the root of R^2 - R - 1 = 0.
"""
import json
import math

import pytest

from conftest import ROOT
from pixelkit.errors import ConfigError
from pixelkit.families.ratio.design import load_ratio_design
from pixelkit.families.ratio.experiment import run_ratio_experiment
from pixelkit.families.ratio.law import counter, interval_over_tau, ratio_from_count, ratio_from_interval

DESIGN = ROOT / "designs" / "ratio_pixel.toml"


@pytest.fixture(scope="module")
def result():
    return run_ratio_experiment(load_ratio_design(DESIGN))


def test_loop_ratio_follows_photocurrent_ratio_at_20nA(result):
    """1:1 .. 1:30 (both directions, both pairs) within 5 % at the nominal bias."""
    assert result["i_bias_A"] == pytest.approx(20e-9)
    rows = [c for c in result["biases"][0]["cells"] if c["role"] == "ratio"]
    assert max(max(c["rf"], 1 / c["rf"]) for c in rows) == pytest.approx(30)
    assert result["ratio_law_max_err_frac"] < 0.05


def test_counter_interval_follows_the_derived_law(result):
    assert result["interval_law_max_err_frac"] < 0.05
    for c in result["biases"][0]["cells"]:
        if c["role"] == "ratio":
            assert math.copysign(1, c["interval_s"]) == math.copysign(1, c["rf"] - 1) or c["rf"] == 1


def test_counts_decode_to_the_true_ratio_within_one_count(result):
    """Behavioural counter on the SPICE intervals, then the decoder: count n brackets R_F
    between the decoded n and n + 1 (the law's 5 % allowed at the edges)."""
    for c in result["biases"][0]["cells"]:
        if c["role"] != "ratio":
            continue
        n, rf = abs(c["count"]), max(c["rf"], 1 / c["rf"])
        assert ratio_from_count(n, 1.0, 1.0) <= 1.05 * rf
        assert rf <= 1.05 * ratio_from_count(n + 1, 1.0, 1.0)
        assert (c["count"] < 0) == (c["rf"] < 1) or n == 0


def test_resolution_with_t_lsb_equal_tau(result):
    golden = (1 + math.sqrt(5)) / 2
    assert result["rf_min"] == pytest.approx(golden, rel=1e-12)
    assert result["rf_min"] == pytest.approx(1.62, abs=0.005)           # paper
    assert result["dr_adj_db"] == pytest.approx(25.6, abs=0.1)          # paper: 20 log10(31 / 1.62)
    assert result["rf_min_spice"] == pytest.approx(golden, rel=0.03)    # SPICE interval = one T_LSB


def test_high_bias_leaves_weak_inversion_and_turns_intensity_dependent(result):
    """At 100 nA the same scene is off the law, and the error depends on the light level."""
    nom, high = result["biases"]
    assert high["i_bias_A"] == pytest.approx(100e-9)
    assert high["ratio_law_max_err_frac"] > 0.1 > 2 * nom["ratio_law_max_err_frac"]
    errs = [x["err_frac"] for x in high["intensity_sweep"]]
    assert max(errs) - min(errs) > 0.1
    assert errs[0] > errs[-1], "brighter light restores the ratio (paper: 'the higher the illumination...')"


def test_decoder_and_counter():
    for rf in (1 / 30, 0.2, 1.0, 1.618, 7.0, 30.0):
        assert ratio_from_interval(interval_over_tau(rf)) == pytest.approx(rf, rel=1e-12)
    assert counter(100e-6, 1e-6, 5) == 31                # saturates at 2^5 - 1
    assert counter(-3.5e-6, 1e-6, 5) == -3
    assert ratio_from_count(31, 1.0, 1.0) == pytest.approx((31 + math.sqrt(31 ** 2 + 4)) / 2)


def test_bad_design_names_the_field(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text(DESIGN.read_text().replace('i_bias_high = "100 nA"', 'i_bias_high = "10 nA"'))
    with pytest.raises(ConfigError, match="readout.i_bias_high"):
        load_ratio_design(p)
    p.write_text(DESIGN.read_text().replace('family = "ratio"', 'family = "tetrachromat"'))
    from pixelkit.family import family_of
    with pytest.raises(ConfigError, match="family"):
        family_of(p)


def test_cli_simulate_json(cli, result, tmp_path):
    wave = tmp_path / "ratio.csv"
    code, out, err = cli("simulate", DESIGN, "--json", "--waveforms", wave)
    assert code == 0, err
    data = json.loads(out)
    assert data["family"] == "ratio"
    assert {"ratio_law_max_err_frac", "rf_min", "dr_adj_db"} <= set(data)
    assert data["waveforms"] == str(wave) and wave.read_text().startswith("time_s,")


def test_regress_baseline_flags_a_changed_column(tmp_path, cli, result):
    """The family goes through `pixelkit regress` like the dual pixel: C_par 30 -> 40 fF moves tau."""
    base = tmp_path / "baseline.json"
    code, out, err = cli("regress", DESIGN, "--baseline", base, "--update")
    assert code == 0, err
    code, out, err = cli("regress", DESIGN, "--baseline", base, "--json")
    assert code == 0, err
    assert json.loads(out)["changed"] == []
    changed = tmp_path / "d.toml"
    changed.write_text(DESIGN.read_text().replace('c_par = "30 fF"', 'c_par = "40 fF"'))
    code, out, err = cli("regress", changed, "--baseline", base, "--json")
    assert code == 1, err
    assert "tau_s" in {r["figure"] for r in json.loads(out)["changed"]}


def test_dual_pixel_commands_refuse_a_family_design_clearly(cli):
    code, out, err = cli("run", DESIGN)
    assert code == 2 and "family = 'ratio'" in err and "Traceback" not in err
