"""The fuzz holes of issue 26, one test each: values no chip, lens or measurement has, refused by
every command that reads them with one line naming the field (exit 2), and no library warning
shown with the kit's source lines.

The expectations are physical, stated here, not the kit's ranges: a photocurrent that fills
the well 1e300 times, an integration of 11.6 days, a negative photocurrent, an infinite
wavelength, a column line without capacitance, a sizing without margin or a zero time ratio,
a zero exposure.
"""
import json
import math
import re
import warnings

import numpy as np
import pytest

from conftest import REF, ROOT

HEADER = "array,row,col,i_ph_A,t_int_s,t_wait_s,temp_C,probe,i_ph_prev_A,v_V\n"
GOOD = "primary,0,0,1e-12,1e-3,1e-3,25,pixel,1e-12,1.0\n"


@pytest.mark.parametrize("col,value", [("i_ph_A", "1e300"), ("t_int_s", "1e6"), ("t_wait_s", "1e6"),
                                       ("i_ph_prev_A", "-1e-12"), ("i_ph_prev_A", "1e300")])
@pytest.mark.parametrize("command", ["predict", "diagnose"])
def test_gap_predict_and_diagnose_share_one_validation(tmp_path, cli, col, value, command):
    names = HEADER.strip().split(",")
    row = GOOD.strip().split(",")
    row[names.index(col)] = value
    p = tmp_path / "rows.csv"
    p.write_text(HEADER + GOOD + ",".join(row) + "\n")
    opt = "--conditions" if command == "predict" else "--measured"
    code, out, err = cli("gap", command, REF, opt, p, "--out", tmp_path / "o", "--json")
    assert code == 2, (code, err[-500:])
    assert f"row 2, column '{col}'" in json.loads(out)["error"] and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("old,new,field", [
    ('column_cap = "200 fF"', 'column_cap = "0 fF"', "pixel.column_cap"),
    ("t_ratio = 12", "t_ratio = 0", "sizing.t_ratio"),
    ("margin = 0.05", "margin = 0", "sizing.margin"),
])
def test_zero_where_zero_means_nothing_real(tmp_path, cli, old, new, field):
    text = REF.read_text()
    assert re.search(re.escape(old), text), old
    p = tmp_path / "d.toml"
    p.write_text(text.replace(old, new, 1))
    code, out, err = cli("models", p)
    assert code == 2 and f"{field} = " in err and len(err.strip().splitlines()) == 1, err


def test_qe_curve_with_an_infinite_wavelength_is_refused(tmp_path, cli):
    from pixelkit.tech import load_technology
    folder = load_technology("c35_thesis").models.folder
    tech = (ROOT / "pixelkit" / "tech" / "builtin" / "c35_thesis.toml").read_text()
    tech = re.sub(r"^folder = .*$", lambda _m: f'folder = "{folder}"', tech, count=1, flags=re.M)
    t = tmp_path / "t.toml"
    t.write_text(tech.replace("[1100, 0.01]]", "[inf, 0.01]]"))
    d = tmp_path / "d.toml"
    d.write_text(REF.read_text().replace('"c35_thesis"', f'"{t}"'))
    code, out, err = cli("models", d)
    assert code == 2 and "photodiode.qe_curve" in err and "finite" in err, err


@pytest.mark.parametrize("value", ["0", "-1e-3", "nan", "inf"])
def test_array_zero_exposure_is_a_usage_error(cli, value):
    code, out, err = cli("array", REF, "--t-exp", value)
    assert code == 2 and "--t-exp" in err and "Traceback" not in err and "internal error" not in err, err


@pytest.mark.parametrize("value", ["0", "-0.5", "nan", "inf", "-inf"])
def test_array_settling_limit_must_be_a_finite_positive_number(cli, value):
    """An infinite limit would let a frame that does not settle read ``ok`` (issue 27): refused, as NaN and <= 0;
    skipping the measurement is ``--no-settling``, whose verdict says settling was not measured."""
    code, out, err = cli("array", REF, "--settling-limit", value)
    assert code == 2 and "--settling-limit" in err and "Traceback" not in err and "internal error" not in err, err


def test_where_trends_fit_picoamperes_without_a_warning():
    """The trend slope of residuals against a photocurrent in pA (x spans 1e-12): no RankWarning
    (the fit is made on x scaled to a span of 1) and the slope equals the least-squares one."""
    from pixelkit.gap.where import breakdown
    rng = np.random.default_rng(1)
    n = 40
    i = np.linspace(1e-12, 5e-12, n)
    resid = 2e-3 * (i - i.mean()) / np.ptp(i) + rng.normal(0, 1e-5, n)
    X = {"arr": np.zeros(n, int), "col": np.arange(n) % 4, "row": np.arange(n) % 5, "afe": np.zeros(n, bool),
         "signal": np.linspace(0.1, 1.0, n), "t_int": np.full(n, 1e-3), "t_wait": np.full(n, 1e-3),
         "T": np.full(n, 25.0), "i": i}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rows = breakdown(X, resid)
    trend = next(r for r in rows if r["factor"] == "trend vs i" and r["level"].startswith("all rows"))
    slope = np.sum((i - i.mean()) * (resid - resid.mean())) / np.sum((i - i.mean()) ** 2)   # by hand
    assert math.isclose(trend["mean_V"], slope * np.ptp(i), rel_tol=1e-6)


def test_a_warning_that_reaches_the_user_is_one_line_without_source(tmp_path):
    """Any library warning is printed as one line naming its kind, never a line of the kit's code."""
    import subprocess
    import sys
    code = ("import warnings, numpy as np\nfrom pixelkit.cli import common\n"
            "common.main.command('warnme')(lambda: np.polyfit(np.array([1e-12, 1e-12, 2e-12]), np.ones(3), 2))\n"
            "common.run(['warnme'])\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       env={**__import__("os").environ, "PYTHONPATH": str(ROOT)})
    lines = p.stderr.strip().splitlines()
    assert any("RankWarning" in ln for ln in lines), p.stderr
    assert all(ln.startswith("pixelkit:") for ln in lines), p.stderr
