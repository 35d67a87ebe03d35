"""Rolling-shutter distortion and its two-sensor compensation.

Independent path: ``pixelkit.sensor.exposure``, a row-by-row, time-stepped
exposure of the moving rectangle (no closed form inside). The closed forms of
``pixelkit.sensor.rolling`` (derived in its docstring) and the compensation of
``pixelkit.sensor.compensation`` must agree with those images within one pixel;
the published forms of [Rychazhnikov2008a] / [Rychazhnikov2008b] are shown to fail where docs/frame-models.md says.
"""
import itertools
import json
import math

import numpy as np
import pytest
from sensor_cli import run_inprocess

from pixelkit.sensor import compensation, rolling
from pixelkit.sensor.rolling_image import measure_horizontal, measure_vertical, simulate
from pixelkit.sensor.rolling_pair import study
from pixelkit.sensor.timing import ShutterTiming

H_OBJ = 12.0
# windows on both sides of h (H > h, H < h) and speeds on both sides of h = s H
GRID = list(itertools.product([0.1, 0.35, 0.7], [4.0, 25.0, 60.0]))


@pytest.mark.parametrize("direction", ["down", "up"])
def test_vertical_closed_forms_match_image_within_one_pixel(direction):
    regimes = set()
    for s, window in GRID:
        m = measure_vertical(simulate(H_OBJ, window, s, direction))
        k = rolling.vertical(H_OBJ, window, s, direction)
        for q in ("total", "edge", "flat"):
            assert abs(m[f"{q}_rows"] - k[f"{q}_rows"]) <= 1.0, (s, window, q, m, k)
        regimes.add((window > H_OBJ, s * window > H_OBJ))
    assert regimes == {(False, False), (True, False), (True, True)}


def test_published_forms_fail_where_the_readme_says():
    # [Rychazhnikov2008a] eq. 1 (edges for H > h) misses the scan's own travel: the image edge is h/(1-s), not s h/(1-s)
    s, window = 0.5, 60.0
    m = measure_vertical(simulate(H_OBJ, window, s, "down"))
    pub = rolling.published_vertical(H_OBJ, window, s, "down")
    assert m["edge_rows"] - pub["edge_rows"] > 5
    # [Rychazhnikov2008b]'s L_up = s(H+h)/(1+s) + h is too long by 2 s h / (1 + s)
    m = measure_vertical(simulate(H_OBJ, window, s, "up"))
    pub = rolling.published_vertical(H_OBJ, window, s, "up")
    assert pub["total_rows"] - m["total_rows"] == pytest.approx(2 * s * H_OBJ / (1 + s), abs=1.0)
    # [Rychazhnikov2008a]'s base angle atan(h / (s H)) depends on H; the image's lean does not
    mh = measure_horizontal(simulate(H_OBJ, window, s, "right", l=10))
    assert mh["base_angle_deg"] == pytest.approx(math.degrees(math.atan(1 / s)), abs=0.5)
    assert abs(rolling.published_horizontal(H_OBJ, 10, window, s)["base_angle_deg"] - mh["base_angle_deg"]) > 20


def test_horizontal_closed_forms_match_image_within_one_pixel():
    for i, (s, window) in enumerate(GRID):
        l = (6.0, 20.0)[i % 2]          # narrower and wider than s H
        m = measure_horizontal(simulate(H_OBJ, window, s, "right", l=l))
        k = rolling.horizontal(H_OBJ, l, window, s)
        for q in ("edge_cols", "row_extent_cols", "flat_cols", "border_shift_cols", "total_cols", "total_rows"):
            assert abs(m[q] - k[q]) <= 1.0, (s, window, l, q, m[q], k[q])
        assert m["shift_per_row"] == pytest.approx(s, abs=0.01)


@pytest.mark.parametrize("direction", ["down", "up"])
def test_compensation_recovers_height_speed_and_position(direction):
    for s, window in GRID:
        r = study(H_OBJ, window, s, direction)["numbers"]
        assert abs(r["compensated_h_rows"] - H_OBJ) <= 1.0, (s, window, r)
        assert r["compensated_speed"] == pytest.approx(s, abs=0.02)
        assert abs(r["image_centre_row"] - r["true_centre_row"]) <= 1.0
    # the article's quadratic, solved as printed, does not give h in the H > h regime
    r = study(H_OBJ, 60.0, 0.35, direction)["numbers"]
    assert r["published_quadratic_h_rows"] is not None and abs(r["published_quadratic_h_rows"] - H_OBJ) > 1.0
    # ... and in the H < h regime it has no root in (0, L') at all
    assert study(20.0, 8.0, 0.3, direction)["numbers"]["published_quadratic_h_rows"] is None


def test_compensated_vertical_image_has_the_true_height():
    out = study(H_OBJ, 25.0, 0.35, "down")
    col = out["frames"]["compensated"][:, out["frames"]["compensated"].shape[1] // 2]
    from pixelkit.sensor.profile import trapezoid
    assert abs(trapezoid(col)["total"] - H_OBJ) <= 1.0


def test_horizontal_compensation_equals_global_shutter_image():
    for s, window in GRID[::2]:
        r = study(H_OBJ, window, s, "right", l=10)["numbers"]
        assert r["compensated_vs_global_max_edge_cols"] <= 1.0, (s, window, r)
        assert abs(r["compensated_shift_per_row"]) < 0.02
        assert abs(r["compensated_h_rows"] - H_OBJ) <= 1.0
        assert r["compensated_speed"] == pytest.approx(s, abs=0.01)


def test_linear_relation_is_exact_on_the_closed_forms():
    """The two size formulas of the kit determine (h, s) uniquely: the relation inverts them."""
    for h, window, s in itertools.product([3.0, 12.0, 40.0], [2.0, 30.0], [0.05, 0.5, 0.9]):
        lo, hi = (rolling.vertical(h, window, s, d)["total_rows"] for d in ("up", "down"))
        c = compensation.vertical(lo, hi, window)
        assert c["h_rows"] == pytest.approx(h, rel=1e-12) and c["speed"] == pytest.approx(s, rel=1e-12)


def test_timing_rows_and_blanking():
    t = ShutterTiming("rolling_shutter", 960, 1650, 22e6, t_int=200e-6, v_blank=30)
    assert t.t_frame == pytest.approx(990 * 1650 / 22e6)
    e = t.exposure()
    assert np.allclose(e[:, 1] - e[:, 0], 200e-6) and np.allclose(np.diff(e[:, 1]), 1650 / 22e6)
    g = ShutterTiming("global", 960, 1650, 22e6, t_int=200e-6, t0=1e-6)
    assert g.storage_wait()[500] == pytest.approx(1e-6 + 500 * 1650 / 22e6)
    r = ShutterTiming("rolling_readout", 10, 100, 1e6, scan="up")
    assert r.read_times()[-1] == 0 and np.allclose(r.read_times() - r.reset_times(), r.t_frame)
    from pixelkit.errors import ConfigError
    with pytest.raises(ConfigError, match="t_int"):
        ShutterTiming("rolling_shutter", 10, 100, 1e6, t_int=2e-3)      # longer than the 1 ms frame
    with pytest.raises(ConfigError, match="mode"):
        ShutterTiming("electronic", 10, 100, 1e6, t_int=1e-4)


def test_cli_rolling_json_and_errors(capsys, tmp_path):
    code, out, err = run_inprocess(capsys, "sensor", "rolling", "--h", "12", "--window", "25", "--speed", "0.35",
                         "--direction", "up", "--json", "--out", tmp_path / "r.png")
    assert code == 0, err
    r = json.loads(out)
    for k in ("model_total_rows", "image_total_rows", "model_edge_rows", "image_edge_rows",
              "compensated_h_rows", "compensated_speed"):
        assert k in r
    assert abs(r["compensated_h_rows"] - 12) <= 1 and (tmp_path / "r.png").stat().st_size > 1000
    code, out, err = run_inprocess(capsys, "sensor", "rolling", "--h", "12", "--window", "25", "--speed", "1.2",
                                   "--direction", "up")
    assert code == 2 and "--speed" in err and "1.2" in err


def test_article_quadratic_against_its_own_size_formulas():
    """Derivation check: eliminating s from L = s(H+h)/(1 -+ s) + h gives 2h^2 - (L' + 3L'')h + ...;
    the printed coefficient (3L' + L'') does not return h even on the article's own sizes."""
    import numpy as np
    h, window, s = 12.0, 60.0, 0.5
    lc = rolling.published_vertical(h, window, s, "up")["total_rows"]
    ls = rolling.published_vertical(h, window, s, "down")["total_rows"]
    c0 = 2 * lc * ls - window * (ls - lc)
    assert min(abs(np.roots([2, -(lc + 3 * ls), c0]) - h)) < 1e-9
    assert min(abs(np.roots([2, -(3 * lc + ls), c0]) - h)) > 5
