"""``pixelkit verify`` on the ratio family: chip power at the design's frame rate (issue 31)."""
import json
from dataclasses import replace

import pytest

from conftest import ROOT, run_cli

RATIO = ROOT / "designs" / "ratio_pixel.toml"
NOMINAL = ("--corners", "tt", "--temperatures", "27degC", "--supplies", "0%")


@pytest.fixture(scope="module")
def ratio():
    from pixelkit.families.ratio.design import load_ratio_design
    return load_ratio_design(RATIO)


def test_ratio_power_spice_against_charge_conservation(ratio):
    # independent path: bias currents x supply (every coulomb of the tails comes from the supply
    # in the periodic steady state); the broken variant (no recharge slot) is caught by the same check
    from pixelkit.families.ratio import power
    r = power.measure(ratio)
    est = r["estimate"]["chip_blocks_W"]
    for b in ("read", "bias", "photo"):
        assert r["chip_blocks_W"][b] == pytest.approx(est[b], rel=0.03), b
    # direction: the read block follows the loop bias, the photo block does not move with it
    hi = power.measure(replace(ratio, readout=replace(ratio.readout, i_bias=2 * ratio.readout.i_bias,
                                                      i_bias_high=4 * ratio.readout.i_bias)))
    assert hi["chip_blocks_W"]["read"] == pytest.approx(2 * r["chip_blocks_W"]["read"], rel=0.05)


def test_ratio_power_first_slot_only_is_caught(ratio):
    # the deliberately broken bench: the slot measured without the recharge of the lines its
    # discharge left (the first slot) misses charge, and the cross-check above would fail
    import numpy as np
    from pixelkit.families.ratio import power
    from pixelkit.spice import simulate_many
    res = simulate_many([power.bench(ratio)], jobs=1)[0]
    t_row = power.row_period(ratio)
    m = res.time <= t_row
    p = -ratio.tech.supply * np.asarray(res["i(vdd_read)"])
    first = float(np.trapezoid(p[m], res.time[m])) / t_row * ratio.array.cols
    assert abs(first / power.estimate(ratio)["chip_blocks_W"]["read"] - 1) > 0.03


def _design(tmp_path, text):
    p = tmp_path / "ratio.toml"
    p.write_text(RATIO.read_text() + text)
    return p


def test_ratio_verify_reference_passes_and_impossible_spec_fails(tmp_path):
    code, out, err = run_cli("verify", RATIO, *NOMINAL, "--out", tmp_path / "ok", "--json")
    assert code == 0, err
    r = json.loads(out)
    assert r["rows"][0]["spec"] == "power_chip" and r["rows"][0]["status"] == "pass"
    assert r["power"]["chip_W"] < 0.6e-3
    p = _design(tmp_path, '\n[spec.array_tight]\nfigure = "power_chip"\nmax = "100 uW"\n')
    code, out, err = run_cli("verify", p, *NOMINAL, "--out", tmp_path / "bad")
    assert code == 1 and "array_tight" in err and "tt 27degC" in err, err


@pytest.mark.parametrize("extra, key", [
    ('\n[spec.cg]\nfigure = "conversion_gain_primary"\nmin = "1 uV/e-"\n', "spec.cg.figure"),
    ('', "array.frame_rate"),
])
def test_ratio_verify_bad_input(tmp_path, extra, key):
    text = RATIO.read_text() + extra
    if key == "array.frame_rate":
        text = text.replace('frame_rate = "9600 Hz"', 'frame_rate = "20000 Hz"')
    p = tmp_path / "r.toml"
    p.write_text(text)
    code, _, err = run_cli("verify", p, *NOMINAL, "--out", tmp_path / "o")
    assert code == 2 and key in err, err


def test_ratio_verify_refuses_monte_carlo(tmp_path):
    code, _, err = run_cli("verify", RATIO, *NOMINAL, "--mc", "5", "--out", tmp_path / "o")
    assert code == 2 and "--mc" in err, err
