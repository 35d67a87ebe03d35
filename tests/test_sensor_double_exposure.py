"""Double exposure with the dual pixel: images of a passing car and the speed from its trace.

Independent paths: the scene's true speed (the image is a time-stepped exposure
of the moving headlight, ``pixelkit.sensor.exposure``, with shot and kTC noise),
and SPICE: the background of the images, rendered through the sizing level's response,
against a SPICE run of the dual-pixel bench at the background's photocurrents over the
images' own exposure times (not the short-window sweep the response and the sizing come from).
"""
import json

import numpy as np
import pytest
from sensor_cli import run_inprocess

from pixelkit.circuits.testbench import dual_pixel_bench, timings
from pixelkit.measure.pixel import double_sampled
from pixelkit.optimize.sizing import light
from pixelkit.sensor import double_exposure as de
from pixelkit.spice import simulate


@pytest.fixture(scope="module")
def sized(ref_design):
    return de.exposure_times(ref_design, "sizing")


@pytest.mark.parametrize("kmh", [40.0, 90.0, 130.0])
def test_speed_from_secondary_image_within_error_budget(ref_design, sized, kmh):
    r = de.measure(ref_design, de.PassingCar(speed=kmh / 3.6), sized, seed=int(kmh))
    assert abs(r["error_kmh"]) <= r["dv_kmh"]
    assert abs(r["error_kmh"]) <= r["dv_pixel_only_kmh"]       # even without the dc term
    assert abs(r["trace_error_px"]) < 1.0


def test_images_meet_the_sizing_criterion_on_the_background_in_spice(ref_design, sized, experiment):
    """Independent reference: SPICE at the images' own times. The background's photocurrents
    (background irradiance x photoactive area: PD on the primary, mask opening on the secondary)
    simulated over t_p and t_s with the transfers aligned; (signal - pedestal) / swing, read
    here at the sample instants, must be the image's median background (0.5 / 0.05 by the
    sizing) within 0.01 / 0.002 of swing (shot and kTC noise of the render, the median of a
    few hundred pixels)."""
    d = ref_design
    r = de.render(d, de.PassingCar(), sized, seed=1)
    im = r["images"]
    bg_p = im["primary"][:, -8:]            # right of the car's front: the static background
    bg_s = im["secondary"][:, -24:]
    j = light(d).j_bg
    tm = timings(d, sized["t_primary_s"], 1, sized["t_secondary_s"])
    run = simulate(dual_pixel_bench(d, j * d.primary.photoactive_area, j * sized["opening_m2"],
                                    title="car_background", tm=tm))
    spice = {}
    for which, col in (("primary", "col_p"), ("secondary", "col_s0")):
        e = experiment[which]
        spice[which] = (double_sampled(run, col, tm[which]) - e["pedestal_V"]) / e["swing_V"]
    assert np.median(bg_p) == pytest.approx(spice["primary"], abs=0.01)
    assert np.median(bg_s) == pytest.approx(spice["secondary"], abs=0.002)
    assert spice["primary"] == pytest.approx(d.experiment.mid_fraction, abs=0.01)
    assert spice["secondary"] == pytest.approx(d.experiment.low_fraction, abs=0.002)
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
