"""``pixelkit close`` on two small problems whose answer is known without close:

- a known optimum from a derivation: the smallest op-amp gain that keeps the SC AFE's gain error
  within 0.5 %, with the feedback capacitor C13 free too. Charge balance at the summing node
  (derived here, not taken from the kit) gives the error eps / (1 + eps), eps = (C11 + C13) /
  (A C13): the error falls with C13, so the optimum puts C13 at its upper bound and
  A* = (C11 + C13) (1 - e) / (e C13) with e = 0.5 %. The SPICE bench sits 1.4 % above the formula
  (docs/verify.md: 0.202 % against 0.200 % at A = 1000, its switches' charge), so close must land
  within 3 % of A*; the revision it writes is then re-verified by ``pixelkit verify`` alone.
- an infeasible set: the primary full well >= 192 ke- and its image lag <= 0.1 % at -10 % supply
  with the PD reset level as the only knob. Measured apart from close (``measure_at`` at
  tt 27 degC -10 %, a sweep of v_pd_reset): 1.9 V gives 173.7 ke- with no lag, 2.0 V 190.0 ke-
  with 0.225 % lag, and the lag crosses 0.1 % near 1.99 V (189 ke-): no level gives both, so close
  must exit 1 naming both specs.
"""
import json

import pytest

from conftest import REF
from pixelkit.schema import to_toml


def _design(tmp_path, spec, verify, close, name="d.toml"):
    """The reference design's file (its comments kept) with these [verify], [spec] and [close] tables."""
    p = tmp_path / name
    p.write_text(REF.read_text().split("\n[verify]")[0] + "\n" + to_toml({"verify": verify, "spec": spec,
                                                                          "close": close}))
    return p


def test_close_finds_the_derived_optimum_and_verify_passes_what_it_wrote(tmp_path, cli):
    e, c11, c13_max = 0.005, 500e-15, 1e-12
    a_star = (c11 + c13_max) * (1 - e) / (e * c13_max)
    p = _design(tmp_path, {"afe_gain_error": {"max": "0.5 %"}},
                {"corners": ["tt"], "temperatures": ["27 degC"], "supplies": ["0 %"], "mc": 0},
                {"objective": "min afe.gain", "tolerance": "0.5 %",
                 "knobs": {"afe.gain": ["100 V/V", "10000 V/V"], "afe.c13": ["250 fF", "1 pF"]}})
    out = tmp_path / "closed_revB.toml"
    code, stdout, err = cli("close", p, "--out", out, "--json")
    assert code == 0, err
    r = json.loads(stdout)
    assert r["status"] == "closed" and r["passes"], r["status"]
    knobs = {k["key"]: k for k in r["knobs"]}
    assert knobs["afe.c13"]["at_bound"] == "max"
    from pixelkit.units import quantity
    a = quantity(knobs["afe.gain"]["value"], "1", "afe.gain")
    assert a == pytest.approx(a_star, rel=0.03), (a, a_star)
    # the path: every candidate with its knobs and each spec's worst margin and where
    path = json.loads((tmp_path / "closed_revB.close.json").read_text())
    assert path["iterations"][0]["mode"] == "start" and len(path["iterations"]) >= 3
    assert all("afe_gain_error" in it["specs"] and it["specs"]["afe_gain_error"]["where"] for it in path["iterations"])
    # the revision: the source's text with the knobs replaced (comments kept), and verify alone passes it
    text = out.read_text()
    assert "# Reference design: the dual-pixel 5T" in text and 'name = "closed_revB"' in text
    assert f'gain = "{knobs["afe.gain"]["value"]}"' in text and 'c13 = "1 pF"' in text
    code, stdout, err = cli("verify", out, "--out", tmp_path / "v", "--json")
    assert code == 0, err
    rows = json.loads(stdout)["rows"]
    assert rows[0]["status"] == "pass" and rows[0]["margin"] >= 0
    _report_section(tmp_path, out, path)


def _report_section(tmp_path, out, path):
    """The report's closure section reads the path beside the revision; it says when the file is not the
    one close wrote, and is unavailable for a design close did not write."""
    from pixelkit.design import load_design
    from pixelkit.report.build import build_section
    from pixelkit.report.sections import Context

    def section(design_file):
        (tmp_path / "rep").mkdir(exist_ok=True)
        return build_section("closure", "t", "o", Context(load_design(design_file), tmp_path / "rep"), {}, False)[0]
    s = section(out)
    assert s.available and s.data["same_file"] and s.data["final"] == path["final"]
    assert {t.name for t in s.tables} >= {"closure_knobs", "closure_path", "closure_margins"}
    assert len(next(t for t in s.tables if t.name == "closure_path").rows) == len(path["iterations"])
    out.write_text(out.read_text() + "# edited by hand\n")
    s = section(out)
    assert s.available and not s.data["same_file"] and "differs from the one close wrote" in " ".join(s.text)
    assert not section(REF).available


def test_close_reports_an_infeasible_set_naming_the_conflicting_specs(tmp_path, cli):
    p = _design(tmp_path, {"full_well_primary": {"min": "192 ke-"}, "image_lag_primary": {"max": "0.1 %"}},
                {"corners": ["tt"], "temperatures": ["27 degC"], "supplies": ["-10 %"], "mc": 0},
                {"objective": "min power", "tolerance": "3 %", "knobs": {"pixel.v_pd_reset": ["1.6 V", "2.2 V"]}})
    out = tmp_path / "b.toml"
    code, stdout, err = cli("close", p, "--out", out, "--json")
    assert code == 1, err
    r = json.loads(stdout)
    assert r["status"] == "infeasible" and not r["passes"]
    assert {s["spec"] for s in r["conflict"]["specs"]} == {"full_well_primary", "image_lag_primary"}
    assert "full_well_primary" in err and "image_lag_primary" in err
    k = r["conflict"]["knobs"][0]
    assert k["raising_helps"] == ["full_well_primary"] and k["raising_hurts"] == ["image_lag_primary"]
    # the best compromise's margins, one of them short; no revision written, the path kept
    assert min(s["margin_pct"] for s in r["final"].values()) < 0
    assert not out.exists() and json.loads((tmp_path / "b.close.json").read_text())["status"] == "infeasible"


@pytest.mark.parametrize("choose", ["screen", "all"])
def test_a_circuit_choice_closes_what_the_supply_driven_gates_cannot(tmp_path, cli, choose):
    """The same two specs with the gates' drive free: from the supply the set stays infeasible (as above,
    from the cache), from a boosted rail (pixel.v_gate, absent in the reference, starts at the middle of
    its bounds) the reset is hard at -10 % supply and both pass; close keeps that choice, writes the rail
    into [pixel] and verify alone passes the file. ``choose = "screen"`` (default): the supply, listed
    first, is simulated on the grid, the rail's start at the same conditions; on the rows the choice moves
    the rail is nowhere behind the supply, the supply is behind on the lag (6.12 % at -10 %), so the rail
    is closed first and, passing, ends the search: the supply is screened, not closed. ``choose =
    "all"``: both are closed, the supply infeasible naming the lag."""
    p = _design(tmp_path, {"full_well_primary": {"min": "192 ke-"}, "image_lag_primary": {"max": "0.1 %"}},
                {"corners": ["tt"], "temperatures": ["27 degC"], "supplies": ["-10 %"], "mc": 0},
                {"objective": "min power", "tolerance": "3 %", "knobs": {"pixel.v_pd_reset": ["1.6 V", "2.2 V"],
                                                     "pixel.gate_drive": {"choices": ["supply", "boosted"]},
                                                     "pixel.v_gate": ["3.0 V", "3.6 V"]}, "choose": choose})
    out = tmp_path / "b.toml"
    code, stdout, err = cli("close", p, "--out", out, "--json")
    assert code == 0, err
    r = json.loads(stdout)
    by = {c["choice"]: c for c in r["choices"]}
    assert by["pixel.gate_drive = boosted"]["chosen"] and by["pixel.gate_drive = boosted"]["passes"]
    if choose == "all":
        assert by["pixel.gate_drive = supply"]["status"] == "infeasible"
        assert "image_lag_primary" in by["pixel.gate_drive = supply"]["conflict"]
    else:
        supply, boosted = by["pixel.gate_drive = supply"], by["pixel.gate_drive = boosted"]
        assert supply["status"] == "screened" and supply["passes"] is None
        assert [c["choice"] for c in r["choices"]] == ["pixel.gate_drive = boosted", "pixel.gate_drive = supply"]
        assert boosted["screen"]["behind_pct"] == 0 and supply["screen"]["behind_pct"] < -100   # lag 6 % vs 0.1 %
        assert supply["screen"]["short_pct"] < boosted["screen"]["short_pct"]
        assert supply["screen"]["worst"].startswith("image_lag_primary")
        assert {i["choice"] for i in r["iterations"]} == {"pixel.gate_drive = boosted"}
    text = out.read_text()
    assert 'gate_drive = "boosted"' in text and "v_gate = " in text
    code, stdout, err = cli("verify", out, "--out", tmp_path / "v", "--json")
    assert code == 0, err


def test_close_raises_the_margin_until_the_yield_interval_clears_min_yield(tmp_path, cli):
    """The derived-optimum problem with a yield to meet: at the nominal optimum (~0.2 % margin) about half
    the capacitor-mismatch draws fail, so close raises the nominal margin target from the samples' spread
    and moves on; the revision's yield interval, as verify alone measures it on the written file with every
    sample, has its lower bound at or above min_yield (all 30 of 30 passing: 88.4 % >= 85 %)."""
    p = _design(tmp_path, {"afe_gain_error": {"max": "0.5 %"}},
                {"corners": ["tt"], "temperatures": ["27 degC"], "supplies": ["0 %"], "mc": 30,
                 "min_yield": "85 %"},
                {"objective": "min afe.gain", "tolerance": "0.5 %", "knobs": {"afe.gain": ["100 V/V", "10000 V/V"]}})
    out = tmp_path / "y.toml"
    code, stdout, err = cli("close", p, "--out", out, "--json")
    assert code == 0, err
    r = json.loads(stdout)
    assert r["status"] == "closed" and r["yield"]["ok"] and r["targets"], r["yield"]
    assert r["targets"][0]["target_pct"] > 1.0           # raised from the 0 % of [close] margin
    code, stdout, err = cli("verify", out, "--mc-full", "--out", tmp_path / "v", "--json")
    assert code == 0, err
    y = json.loads(stdout)["rows"][0]["yield"]
    assert y["samples"] == 30 and y["interval"][0] >= 0.85, y
