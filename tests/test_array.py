"""The 2 x 2 array (fig. 3.13): every subpixel matches its single-pixel simulation."""
import numpy as np
import pytest

from pixelkit.circuits.array import array_bench
from pixelkit.circuits.testbench import dual_pixel_bench, timings
from pixelkit.measure.pixel import double_sampled
from pixelkit.plots.waveforms import plot_columns
from pixelkit.spice import simulate, simulate_many

IP = [[2e-10, 4e-10], [6e-10, 8e-10]]
IS = [[1e-11 * (j + 1) for j in range(6)], [1e-11 * (j + 7) for j in range(6)]]


def test_2x2_matches_single_pixels(ref_design, experiment, tmp_path):
    d = ref_design
    arr = simulate(array_bench(d, IP, IS))
    tm2 = timings(d, d.experiment.t_window, 2)
    tm1 = timings(d, d.experiment.t_window, 1)
    singles = simulate_many([dual_pixel_bench(d, IP[r][c], tuple(IS[r][3 * c:3 * c + 3]), title=f"single{r}{c}")
                             for r in range(2) for c in range(2)])
    checked = 0
    for r in range(2):
        for c in range(2):
            one = singles[2 * r + c]
            got = double_sampled(arr, f"col_p_{c}", tm2["primary"], r)
            ref = double_sampled(one, "col_p", tm1["primary"])
            assert abs(got - ref) <= 0.01 * experiment["primary"]["swing_V"]
            checked += 1
            for k in range(3):
                got = double_sampled(arr, f"col_s_{3 * c + k}", tm2["secondary"], r)
                ref = double_sampled(one, f"col_s{k}", tm1["secondary"])
                assert abs(got - ref) <= 0.01 * experiment["secondary"]["swing_V"]
                checked += 1
    assert checked == 16
    # the signals differ from subpixel to subpixel, as the photocurrents do
    sig = [double_sampled(arr, f"col_s_{j}", tm2["secondary"], 0) for j in range(6)]
    assert np.all(np.diff(sig) > 0)
    png = plot_columns(arr, {"primary": ["col_p_0", "col_p_1"], "secondary": [f"col_s_{j}" for j in range(6)]},
                       tmp_path / "array.png", "2 x 2 readout")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_array_command_against_single_pixel_spice(cli, ref_design, experiment, tmp_path):
    """Independent reference: the single-pixel bench (one dual pixel, its own column loads, its
    own deck) simulated here at each pixel's photocurrent as the command reports it: every
    signal of the 2 x 2 frame (default gradient scene) within 1 % of the swing."""
    import json
    code, out, err = cli("array", "designs/dual_pixel_revA.toml", "--rows", "2", "--cols", "2", "--json",
                         "--out", tmp_path / "o")
    assert code == 0, err
    f = json.loads(out)
    d = ref_design
    n = d.secondary_per_pixel
    ip, is_ = np.array(f["iph_primary_A"]), np.array(f["iph_secondary_A"])
    singles = simulate_many([dual_pixel_bench(d, ip[r, c], tuple(is_[r, n * c:n * c + n]), title=f"cmd_single{r}{c}")
                             for r in range(2) for c in range(2)])
    tm = timings(d, d.experiment.t_window)
    for r in range(2):
        for c in range(2):
            one = singles[2 * r + c]
            assert f["primary_signal_V"][r][c] == pytest.approx(
                double_sampled(one, "col_p", tm["primary"]), abs=0.01 * experiment["primary"]["swing_V"])
            for k in range(n):
                assert f["secondary_signal_V"][r][n * c + k] == pytest.approx(
                    double_sampled(one, f"col_s{k}", tm["secondary"]), abs=0.01 * experiment["secondary"]["swing_V"])
    assert np.ptp(ip) > 1e-9            # the scene spans the swing: the check covers the transfer
