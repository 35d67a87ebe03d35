"""The report's sizing, AFE, array, layout and gap sections (quick profile, built once).

Independent paths, one per check:
- sizing: the sized design simulated in SPICE over its own integration times
  (``optimize.flow.verify``) must land on the design's criterion (mid-scale / 5 % of swing),
  and C_M is the closed form 12 (A_s / A_p)(i_mid / i_5pct) of the experiment's currents;
- AFE: the SPICE bench's gain error against -eps/(1+eps), eps = (C11 + C13)/(A C13), written here;
- array: signals rise along the scene's gradient (physics), and the one-deck frame agrees with
  the frame engine's split decks;
- layout: C_A extracted from the GDS against the thesis's [Thesis2019] 15.1 x 13.55 um / 5 x 5 um;
- gap: a committed SPICE-generated silicon case, whose true effect (truth.json) the section's
  diagnosis must name.
"""
import csv
import json
from pathlib import Path

import pytest

from conftest import REF, ROOT, run_cli

MINE = ("sizing", "afe", "array", "layout")


@pytest.fixture(scope="module")
def report(quick_report):
    q = quick_report
    assert q["sized"][0] == q["sized"][1]   # the report wrote nothing in designs/
    return q["out"], json.loads((q["out"] / "summary.json").read_text())


def _csv(out: Path, name: str) -> list[dict]:
    with open(out / f"{name}.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def _value(summary, name):
    return summary["checked"][name]["value"]


@pytest.mark.parametrize("key,tables,figures", [
    ("sizing", ["sizing_result", "sizing_constraints", "sizing_verify", "sizing_sensitivity"], ["sizing.png"]),
    ("afe", ["afe_summary", "afe_transfer"], ["afe_transfer.png"]),
    ("array", ["array_signals"], ["array_readout.png"]),
    ("bright", ["bright_source"], []),
    ("layout", ["layout_extracted"], ["layout/dual_pixel_revA_dualpix.png", "layout/dual_pixel_revA_dualpix_3d.png"]),
])
def test_section_is_available_with_tables_and_figures(report, key, tables, figures):
    """Structure only: each section's numbers are checked against their references below."""
    out, summary = report
    assert summary["sections"][key] == "available"
    for t in tables:
        assert _csv(out, t), t
    for f in figures:
        assert (out / f).stat().st_size > 1000, f
    assert any(n.startswith(f"{key}.") for n in summary["checked"])


def test_sizing_verifies_on_the_criterion_and_names_binding_constraints(report, ref_design, experiment):
    out, summary = report
    assert _value(summary, "sizing.verify.primary_pct") == pytest.approx(50, abs=2)
    assert _value(summary, "sizing.verify.secondary_pct") == pytest.approx(5, abs=0.5)
    # C_M = 12 (A_s / A_p)(i_mid / i_5pct): the derivation of test_sizing.py, on the report's experiment
    d = ref_design
    a_s_over_a_p = (d.secondary.pd_width * d.secondary.pd_height) / (d.primary.pd_width * d.primary.pd_height)
    assert _value(summary, "sizing.c_m") == pytest.approx(12 * a_s_over_a_p * experiment["ratio"], rel=0.01)
    states = {r["constraint"].split(" ")[0]: r["state"] for r in _csv(out, "sizing_constraints")}
    assert states["t_ratio"] == "binding"                        # the design fixes t_s = 12 t_p
    assert states["motion"] == "slack" and states["trace"] == "slack"
    assert (out / "sized_design.toml").exists()
    assert "skipped" in _csv(out, "sizing_sensitivity")[0]["note"]


def test_afe_gain_error_is_the_finite_gain_closed_form(report, ref_design):
    _, summary = report
    a = ref_design.afe
    eps = (a.c11 + a.c13) / (a.gain * a.c13)
    assert _value(summary, "afe.gain_error_pct") == pytest.approx(-100 * eps / (1 + eps), rel=0.05)


def test_array_signals_follow_the_gradient_and_the_split_decks(report):
    out, summary = report
    rows = _csv(out, "array_signals")
    for kind in ("primary", "secondary"):
        for r in ("0", "1"):
            sig = [float(x["signal (mV)"]) for x in rows if x["array"] == kind and x["row"] == r]
            assert len(sig) >= 2 and all(b > a + 1.0 for a, b in zip(sig, sig[1:])), (kind, r, sig)
    assert _value(summary, "array.worst_split_vs_whole_mV") < 0.5
    # the reference design's read settles (issue 27): the report's figure on the 2 x 2 gradient is within
    # the 0.5 mV limit (the thesis's read, hundreds of mV there, is told from it in test_settling)
    assert abs(_value(summary, "array.settling_worst_mV")) < 0.5
    assert all(x["settling error vs long S1 (mV)"] not in ("", "-") for x in rows)


def test_quick_bright_table_runs_the_design_as_it_is(report, ref_design):
    """The quick profile's bright-source table: both arrays at 1 and 1000 full wells, each with the design's own
    anti-blooming setting only (the reference sets no ``timing.ec_hold``: off); the full profile adds the other
    setting (``tests/test_overexposure.py`` runs both)."""
    out, _ = report
    rows = _csv(out, "bright_source")
    assert not ref_design.primary.timing.ec_hold and not ref_design.secondary.timing.ec_hold
    assert sorted((r["array"], r["anti-blooming"], float(r["full wells"])) for r in rows) == \
        [(k, "off", f) for k in ("primary", "secondary") for f in (1.0, 1000.0)]


def test_layout_c_a_is_the_thesis_ratio(report):
    _, summary = report
    assert _value(summary, "layout.c_a") == pytest.approx(15.1 * 13.55 / 25.0, rel=1e-3)


def test_gap_without_measured_data_says_how_to_get_it(report):
    out, summary = report
    assert summary["sections"]["gap"] == "needs --measured"   # an input not given, not a failure
    assert "Give --measured: M.csv" in (out / "index.html").read_text()


def test_gap_section_names_the_true_effect_of_a_silicon_case(thesis_read_design, tmp_path):
    """A committed virtual-silicon case, diagnosed against the chip it was made from (the thesis's read)."""
    from pixelkit.report.sections import Context, load_section
    cases = ROOT / "pixelkit" / "gap" / "silicon_cases"
    truth = json.loads((cases / "truth.json").read_text())["c1000"]
    with open(cases / "cases.csv", newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r["case"] == "c1000"]
    meas = tmp_path / "m.csv"
    with open(meas, "w", newline="") as fh:
        w = csv.DictWriter(fh, [k for k in rows[0] if k != "case"])
        w.writeheader()
        w.writerows({k: v for k, v in r.items() if k != "case"} for r in rows)
    s = load_section("gap").build(Context(thesis_read_design, tmp_path, measured=meas))
    assert s.available and s.data["best"] == truth["effect"]
    assert {t.name for t in s.tables} >= {"gap_ranking", "gap_where"} and all(t.rows for t in s.tables)
    assert s.figures and all((tmp_path / f.file).exists() for f in s.figures)
    assert (tmp_path / "gap_section.html").exists()
