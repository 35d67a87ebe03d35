"""The [spec] and [verify] tables: refused with the key and what is allowed before anything runs;
yield statistics against the binomial distribution summed directly (independent path)."""
import copy
import json
import math
import tomllib
from pathlib import Path

import pytest

from conftest import REF, run_cli
from pixelkit.design import load_design
from pixelkit.errors import ConfigError
from pixelkit.schema import to_toml

BASE = tomllib.loads(REF.read_text())


def _write(tmp_path: Path, extra: dict, drop_specs=True) -> Path:
    raw = copy.deepcopy(BASE)
    if drop_specs:
        raw.pop("spec", None)
    for k, v in extra.items():
        raw[k] = v
    p = tmp_path / "d.toml"
    p.write_text(to_toml(raw))
    return p


BAD = [  # (what, extra tables, field named in the error, words of what is allowed)
    ("unknown figure", {"spec": {"frobnicate": {"min": "1 V"}}}, "spec.frobnicate", "a figure the kit measures"),
    ("unknown named figure", {"spec": {"x": {"figure": "cg", "min": "1 V"}}}, "spec.x.figure", "conversion_gain_primary"),
    ("unit of another figure", {"spec": {"swing_primary": {"min": "1 uV/e-"}}}, "spec.swing_primary.min",
     "a quantity in V"),
    ("display unit that does not fit", {"spec": {"swing_primary": {"min": "1 V", "unit": "e-"}}},
     "spec.swing_primary.unit", "V, mV, uV"),
    ("min above max", {"spec": {"swing_primary": {"min": "1 V", "max": "500 mV"}}}, "spec.swing_primary.max",
     "a value >= min"),
    ("no limit", {"spec": {"swing_primary": {"typ": "1 V"}}}, "spec.swing_primary", "a min and / or a max"),
    ("corner the library lacks", {"spec": {"swing_primary": {"min": "1 V", "corners": ["tt", "xx"]}}},
     "spec.swing_primary.corners", "a corner of the model library: ff, fs, sf, ss, tt"),
    ("grid corner the library lacks", {"verify": {"corners": ["zz"]}}, "verify.corners", "a corner of the model"),
    ("temperature without unit", {"verify": {"temperatures": [27]}}, "verify.temperatures[0]", "a number with a unit"),
    ("not a list", {"verify": {"supplies": "-10 %"}}, "verify.supplies", "a list of"),
    ("repeated value", {"verify": {"supplies": ["-10 %", "-0.1"]}}, "verify.supplies", "without repeated"),
    ("bad spec name", {"spec": {"a;b": {"min": "1 V"}}}, "spec.a;b", "a name of letters"),
    ("limit that is a table", {"spec": {"swing_primary": {"min": {"value": 1}}}}, "spec.swing_primary.min",
     "a quantity with its unit"),
    ("unknown key", {"spec": {"swing_primary": {"min": "1 V", "minimum": "1 V"}}}, "spec.swing_primary.minimum",
     "no such field"),
    ("mismatch source", {"verify": {"mismatch": "magic"}}, "verify.mismatch", "one of auto, library, pelgrom"),
    # issue 44: limits no real figure reaches always pass (or fail) - refused per figure, in its unit
    ("percentage 1e300", {"spec": {"afe_gain_error": {"max": "1e300 %"}}}, "spec.afe_gain_error.max",
     "strictly between 1e-07 and 100 %"),
    ("zero minimum", {"spec": {"full_well_primary": {"min": "0 ke-"}}}, "spec.full_well_primary.min",
     "strictly between 1 and 1e+09 e-"),
    ("negative minimum", {"spec": {"conversion_gain_primary": {"min": "-3 uV/e-"}}},
     "spec.conversion_gain_primary.min", "strictly between 0.001 and 10000 uV/e-"),
    ("conversion gain 2e4 uV/e-", {"spec": {"pd_conversion_gain_secondary": {"max": "2e4 uV/e-"}}},
     "spec.pd_conversion_gain_secondary.max", "strictly between 0.001 and 10000 uV/e-"),
    ("lag above 100 %", {"spec": {"image_lag_primary": {"max": "150 %"}}}, "spec.image_lag_primary.max",
     "strictly between -100 and 100 %"),
    ("dynamic range 0 dB", {"spec": {"dynamic_range_primary": {"min": "0 dB"}}}, "spec.dynamic_range_primary.min",
     "strictly between 0 and 200 dB"),
    ("power 1e-300 W", {"spec": {"power_chip": {"max": "1e-300 W", "unit": "W"}}}, "spec.power_chip.max",
     "strictly between 1e-15 and 100 W"),
    ("typical 1e300 V", {"spec": {"swing_primary": {"min": "0.5 V", "typ": "1e300 V"}}}, "spec.swing_primary.typ",
     "strictly between 1e-06 and 10 V"),
]


@pytest.mark.parametrize("what,extra,field,allowed", BAD, ids=[b[0] for b in BAD])
def test_bad_spec_is_refused_at_load(tmp_path, what, extra, field, allowed):
    with pytest.raises(ConfigError) as err:
        load_design(_write(tmp_path, extra))
    assert err.value.field == field, str(err.value)
    assert allowed in err.value.allowed, str(err.value)


def test_bad_spec_refused_by_verify_before_any_simulation(tmp_path):
    """exit 2, one line naming the key and what is allowed; the simulation cache stays empty."""
    cache = tmp_path / "cache"
    f = _write(tmp_path, {"spec": {"swing_primary": {"min": "1 V", "corners": ["xx"]}}})
    import os
    import subprocess
    import sys
    p = subprocess.run([sys.executable, "-m", "pixelkit", "verify", str(f), "--json"], capture_output=True, text=True,
                       env={**os.environ, "PIXELKIT_CACHE": str(cache)}, timeout=120)
    assert p.returncode == 2, p.stderr
    obj = json.loads(p.stdout)
    assert obj["field"] == "spec.swing_primary.corners" and "ff, fs, sf, ss, tt" in obj["allowed"]
    assert len(p.stderr.strip().splitlines()) == 1
    assert not any(cache.rglob("*.entry"))


def test_spec_values_in_si_and_in_their_unit(tmp_path):
    d = load_design(_write(tmp_path, {"spec": {
        "cg": {"figure": "conversion_gain_primary", "min": "3.5 uV/e-", "typ": 4.0},
        "dynamic_range_primary": {"min": "60 dB"},
        "full_well_primary": {"min": "200 ke-", "unit": "ke-"},
        "criterion_secondary": {"min": 4, "max": "6 %"}}}))
    s = {x.name: x for x in d.spec}
    q = 1.602176634e-19
    assert s["cg"].lo == pytest.approx(3.5e-6 / q) and s["cg"].typical == pytest.approx(4.0e-6 / q)
    assert s["dynamic_range_primary"].lo == pytest.approx(1000.0)       # 60 dB as an amplitude ratio
    assert s["full_well_primary"].lo == pytest.approx(200e3 * q, rel=1e-9, abs=0)
    assert (s["criterion_secondary"].lo, s["criterion_secondary"].hi) == pytest.approx((0.04, 0.06))
    assert [x.name for x in d.spec] == ["cg", "dynamic_range_primary", "full_well_primary", "criterion_secondary"]


def test_reference_design_specs_load(ref_design):
    names = {s.name for s in ref_design.spec}
    assert {"pd_conversion_gain_primary", "criterion_secondary", "power_chip", "settling_primary"} <= names
    assert ref_design.verify.mc == 200 and len(ref_design.verify.temperatures) == 3


def _binomial_interval(k, n, conf):
    """Clopper-Pearson by bisection on the binomial tail, summed term by term."""
    a = 1 - conf

    def tail_ge(p):   # P(X >= k)
        return sum(math.comb(n, j) * p ** j * (1 - p) ** (n - j) for j in range(k, n + 1))

    def tail_le(p):   # P(X <= k)
        return sum(math.comb(n, j) * p ** j * (1 - p) ** (n - j) for j in range(0, k + 1))

    def solve(f, target, increasing):
        lo, hi = 0.0, 1.0
        for _ in range(80):
            mid = (lo + hi) / 2
            if (f(mid) < target) == increasing:
                lo = mid
            else:
                hi = mid
        return (lo + hi) / 2
    lower = 0.0 if k == 0 else solve(tail_ge, a / 2, True)
    upper = 1.0 if k == n else solve(tail_le, a / 2, False)
    return lower, upper


@pytest.mark.parametrize("k,n", [(0, 10), (5, 10), (10, 10), (97, 100), (180, 200)])
def test_clopper_pearson_against_the_binomial(k, n):
    from pixelkit.verify.yields import clopper_pearson
    assert clopper_pearson(k, n, 0.95) == pytest.approx(_binomial_interval(k, n, 0.95), abs=1e-6)


def test_margin_sigma():
    from pixelkit.verify.yields import margin_sigma
    v = [1.0, 2.0, 3.0]                       # mean 2, sample sigma 1
    assert margin_sigma(v, 0.5, None) == pytest.approx(1.5)
    assert margin_sigma(v, None, 2.5) == pytest.approx(0.5)
    assert margin_sigma(v, 0.0, 2.5) == pytest.approx(0.5)     # the nearer limit
    assert margin_sigma(v, 3.0, None) == pytest.approx(-1.0)


def test_electron_units():
    from pixelkit.units import quantity
    q = 1.602176634e-19
    assert quantity("30 e-", "C", "x") == pytest.approx(30 * q, rel=1e-9, abs=0)
    assert quantity("248 ke-", "C", "x") == pytest.approx(248e3 * q, rel=1e-9, abs=0)
    assert quantity("4 uV/e-", "V/C", "x") == pytest.approx(4e-6 / q)
    with pytest.raises(ConfigError):
        quantity("1 me-", "C", "x")


def test_verify_options_are_checked(tmp_path):
    f = _write(tmp_path, {"spec": {"afe_gain_error": {"max": "1 %"}}})
    for args, field in ((["--corners", "tt,nope"], "--corners"), (["--temperatures", "27"], "--temperatures"),
                        (["--supplies", "-80%"], "--supplies"), (["--temperatures", "1e300 degC"], "--temperatures")):
        code, out, err = run_cli("verify", f, *args, "--json", timeout=120)
        assert code == 2, (args, err)
        assert json.loads(out)["field"] == field, (args, out)
    code, out, err = run_cli("verify", f, "--post-layout", timeout=120)
    assert code == 2 and "[stack]" in err and "post-layout" in err   # c35_thesis has no process stack


def _report_folder(path: Path, checked: dict, rows: list | None):
    path.mkdir(parents=True)
    (path / "summary.json").write_text(json.dumps({"design": "d", "profile": "quick", "checked": {
        k: {"value": v, "unit": "V", "tol_rel": 0.0, "tol_abs": 1e-3, "section": "x", "note": ""}
        for k, v in checked.items()}}))
    if rows is not None:
        (path / "data_signoff.json").write_text(json.dumps({"rows": rows}))
    return path


def _row(name, value, margin_pct, status):
    return {"spec": name, "limit": "<= 1 V", "unit": "V", "value": value, "margin_pct": margin_pct,
            "status": status, "worst": "tt 27degC +0%"}


def test_revision_diff_fails_on_specs_and_ranks_by_margin_used(tmp_path):
    """With specs, figures that moved are listed and do not fail the diff; a spec that passed and
    now fails does; specs are ranked by the margin the revision used. Without specs, a figure that
    moved beyond its tolerance fails it (the former semantics)."""
    from pixelkit.report.diff import diff_reports, load_report
    a = _report_folder(tmp_path / "a", {"x.v": 1.0, "y.v": 2.0},
                       [_row("s1", 0.5, 50.0, "pass"), _row("s2", 0.2, 80.0, "pass"), _row("s3", 2.0, -100, "fail")])
    moved = _report_folder(tmp_path / "b", {"x.v": 1.5, "y.v": 2.0},
                           [_row("s1", 0.7, 30.0, "pass"), _row("s2", 0.6, 40.0, "pass"), _row("s3", 2.0, -100, "fail")])
    d = diff_reports(load_report(a), moved)
    assert d["by_specs"] and d["passed"] and d["moved"] == ["x.v"] and d["newly_failing"] == []
    assert [r["spec"] for r in d["specs"]] == ["s2", "s1", "s3"]          # 40 points used, then 20, then 0
    assert d["specs"][2]["verdict"] == "still failing"
    broke = _report_folder(tmp_path / "c", {"x.v": 1.0, "y.v": 2.0},
                           [_row("s1", 1.2, -20.0, "fail"), _row("s2", 0.2, 80.0, "pass"), _row("s3", 2.0, -100, "fail")])
    d = diff_reports(load_report(a), broke)
    assert not d["passed"] and d["newly_failing"] == ["s1"] and d["specs"][0]["spec"] == "s1"
    plain_a = _report_folder(tmp_path / "pa", {"x.v": 1.0}, None)
    plain_b = _report_folder(tmp_path / "pb", {"x.v": 1.5}, None)
    d = diff_reports(load_report(plain_a), plain_b)
    assert not d["by_specs"] and not d["passed"] and d["moved"] == ["x.v"]


def _tech_with_mim(tmp_path: Path, mim: dict) -> Path:
    """The reference design on a copy of c35_thesis whose [models.mim_corners] is ``mim``."""
    from pixelkit.tech import load_technology
    src = Path(load_technology("c35_thesis").source)
    raw = tomllib.loads(src.read_text())
    raw["models"]["folder"] = str(load_technology("c35_thesis").models.folder)
    raw["models"]["mim_corners"] = mim
    (tmp_path / "t.toml").write_text(to_toml(raw))
    d = tmp_path / "d.toml"
    d.write_text(REF.read_text().replace('"c35_thesis"', json.dumps(str(tmp_path / "t.toml"))))
    return d


def test_mim_corners_scale_the_afe_capacitors_by_the_library_factor(tmp_path, ref_design):
    """The factors are the GF180MCU library's own (sm141064.ngspice: mimcap_ff sets
    mim_corner_2p0fF=0.9, mimcap_ss 1.1, the parameter cap_mim_2f0fF's c_cox is scaled by);
    a condition at ss carries the AFE's capacitors x 1.1, fs (no MIM section named) x 1. A
    section that sets no such parameter, or a corner the library lacks, is refused at load."""
    from pixelkit.verify import conditions
    assert ref_design.tech.mim_corner == {"tt": 1.0, "ff": 0.9, "ss": 1.1}
    a = ref_design.afe
    for corner, k in (("ss", 1.1), ("ff", 0.9), ("fs", 1.0)):
        b = conditions.at(ref_design, conditions.Condition(corner, 300.15, 0.0)).afe
        assert (b.c11, b.c12, b.c13) == pytest.approx((a.c11 * k, a.c12 * k, a.c13 * k), rel=1e-12, abs=0), corner
    with pytest.raises(ConfigError) as e:   # the MOS section sets no MIM factor
        load_design(_tech_with_mim(tmp_path, {"ff": "lib sm141064.ngspice ff"}))
    assert e.value.field == "models.mim_corners.ff" and "mim_corner_2p0fF" in str(e.value)
    with pytest.raises(ConfigError) as e:
        load_design(_tech_with_mim(tmp_path, {"xx": "lib sm141064.ngspice mimcap_ss"}))
    assert e.value.field == "models.mim_corners.xx" and "ff, fs, sf, ss, tt" in str(e.value)
