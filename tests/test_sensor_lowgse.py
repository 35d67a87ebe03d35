"""Low-GSE emulation of the double exposure on a conventional global-shutter sensor.

Independent paths: the thesis's [Thesis2019] printed example (eq. 2.18), a worked
row-gradient example of 1 + t_wait / (GSE t_exp) (480 rows x 10 us, t_exp = 100 us, GSE 300 -> 16 %),
and the time-stepped image (``pixelkit.sensor.exposure``) for the balance.
"""
import json

import pytest
from sensor_cli import run_inprocess

from pixelkit.sensor import lowgse as lg


def test_rule_of_thumb_against_eq_2_18():
    """Eq. 2.17 is the balance integral_0^tau1 eta dt ~ integral_tau1^tau2 eta dt: at t_int = the rule for
    row 500, the time-stepped image of constant light (``sensor.exposure``, each row read at its own
    time) holds as much charge from the row's wait as from the exposure (S(500) / S(0) = 2; row 0
    waits nothing). Eq. 2.18's example, its own numbers 500 x 1650 / 22 MHz / 310 = 0.121 ms, against
    the printed "0.2 ms ~": the same order (1.65x)."""
    cam = lg.Camera()                         # MT9M021: 1650 clocks per row, 22 MHz, GSE 310
    t = lg.rule_of_thumb(cam, 500)
    assert lg.row_profile(cam, t)[500] == pytest.approx(2.0, rel=1e-3)
    assert t == pytest.approx(500 * 1650 / 22e6 / 310, rel=1e-9)
    assert 0.5 < 0.2e-3 / t < 2.0


def test_row_gradient_matches_effects_example():
    cam = lg.Camera(n_rows=480, row_length=10, f_pixclk=1e6, gse=300)
    p = lg.row_profile(cam, 100e-6)
    assert p[-1] - 1 == pytest.approx(0.16, abs=0.002)


def test_image_balance_peaks_at_the_rule():
    b = lg.balance(ratios=(0.125, 0.5, 1.0, 2.0, 8.0))
    assert 0.5 <= b["best_ratio"] <= 2.0
    s = b["sweep"]
    assert s["product"][0] < 0.75 and s["product"][-1] < 0.5      # far from the balance both ways
    assert s["sharpness"] == sorted(s["sharpness"])                # longer exposure: sharper scene ...
    assert s["trace_contrast"] == sorted(s["trace_contrast"], reverse=True)   # ... weaker trace


@pytest.mark.parametrize("ratio", [0.25, 4.0])
def test_speed_from_the_emulated_trace(ratio):
    """Eq. 2.15: the trace drawn during the row's wait gives v = d / t_wait (truth: the scene's speed)."""
    cam, scene = lg.Camera(), lg.StreetScene()
    r = lg.trace_speed(cam, scene, ratio * lg.rule_of_thumb(cam, 500))
    assert abs(r["trace_px"] - r["truth_px"]) < 1.0
    assert r["speed_px_s"] == pytest.approx(scene.speed_px_s, rel=0.01)


def test_cli_lowgse(capsys):
    """The command at a row and GSE of its own: the rule and the wait from eq. 2.14 / 2.17 with the
    command's numbers (row 300, 1650 clocks per row, 22 MHz, GSE 100), the image's balance peak near
    the rule (eq. 2.16: equal weight) and the trace's speed against the scene's truth (eq. 2.15)."""
    code, out, err = run_inprocess(capsys, "sensor", "lowgse", "--row", "300", "--gse", "100", "--json")
    assert code == 0, err
    r = json.loads(out)
    t_wait = 300 * 1650 / 22e6
    assert r["t_wait_s"] == pytest.approx(t_wait, rel=1e-9)
    assert r["t_rule_s"] == pytest.approx(t_wait / 100, rel=1e-9)
    assert 0.5 <= r["best_ratio_image"] <= 2.0
    assert r["trace_speed"]["speed_px_s"] == pytest.approx(lg.StreetScene().speed_px_s, rel=0.01)
    code, out, err = run_inprocess(capsys, "sensor", "lowgse", "--gse", "0.5")
    assert code == 2 and "--gse" in err
