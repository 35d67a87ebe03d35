"""Double exposure with the dual pixel: images of a passing car and the speed from its trace.

Independent paths: the scene's true speed (the image is a time-stepped exposure
of the moving headlight, ``pixelkit.sensor.exposure``, with shot and kTC noise),
and the sizing's 5 % / mid-scale criterion, which the casadi solver meets in
closed form and the image must show on the background.
"""
import json

import numpy as np
import pytest
from sensor_cli import run_inprocess

from pixelkit.sensor import double_exposure as de


@pytest.fixture(scope="module")
def sized(ref_design):
    return de.exposure_times(ref_design, "sizing")


@pytest.mark.parametrize("kmh", [40.0, 90.0, 130.0])
def test_speed_from_secondary_image_within_error_budget(ref_design, sized, kmh):
    r = de.measure(ref_design, de.PassingCar(speed=kmh / 3.6), sized, seed=int(kmh))
    assert abs(r["error_kmh"]) <= r["dv_kmh"]
    assert abs(r["error_kmh"]) <= r["dv_pixel_only_kmh"]       # even without the dc term
    assert abs(r["trace_error_px"]) < 1.0


def test_images_meet_the_sizing_criterion_on_the_background(ref_design, sized):
    r = de.render(ref_design, de.PassingCar(), sized, seed=1)
    im = r["images"]
    bg_p = im["primary"][:, -8:]            # right of the car's front: the static background
    bg_s = im["secondary"][:, -24:]
    assert np.median(bg_p) == pytest.approx(ref_design.experiment.mid_fraction, abs=0.03)
    assert np.median(bg_s) == pytest.approx(ref_design.experiment.low_fraction, abs=0.01)
    assert im["primary"].max() == 1.0                         # the headlight saturates the primary ...
    assert 2 * np.median(bg_s) < im["secondary"].max() < 0.95  # ... and draws an unsaturated trace
    # the superposed image carries the trace too (the chapter-2 scheme on one array)
    row = np.argmax(im["superposed"].max(axis=1))
    assert (im["superposed"][row] > 1.5 * np.median(im["superposed"][:, -8:])).sum() >= 3


def test_design_file_times_also_measure_within_budget(ref_design):
    t = de.exposure_times(ref_design, "design")
    r = de.measure(ref_design, de.PassingCar(speed=60 / 3.6), t, seed=3)
    assert abs(r["error_kmh"]) <= r["dv_kmh"]


def test_cli_car(capsys, tmp_path):
    from conftest import REF
    code, out, err = run_inprocess(capsys, "sensor", "car", REF, "--speed", "70 km/h", "--json",
                                   "--out", tmp_path / "car.png")
    assert code == 0, err
    r = json.loads(out)
    assert abs(r["error_kmh"]) <= r["dv_kmh"] and (tmp_path / "car.png").stat().st_size > 1000
    code, out, err = run_inprocess(capsys, "sensor", "car", REF, "--speed", "-5 km/h")
    assert code == 2 and "--speed" in err
