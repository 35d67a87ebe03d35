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
    cam = lg.Camera()                         # MT9M021: 1650 clocks per row, 22 MHz, GSE 310
    t = lg.rule_of_thumb(cam, 500)
    assert t == pytest.approx(500 * 1650 / 22e6 / 310, rel=1e-12)
    # the thesis set 0.2 ms and wrote "~": same order of magnitude (0.12 ms -> 1.65x)
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
    code, out, err = run_inprocess(capsys, "sensor", "lowgse", "--json")
    assert code == 0, err
    r = json.loads(out)
    assert r["t_rule_s"] == pytest.approx(1.2097e-4, rel=1e-3)
    code, out, err = run_inprocess(capsys, "sensor", "lowgse", "--gse", "0.5")
    assert code == 2 and "--gse" in err
