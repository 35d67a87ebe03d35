"""The design report of a pixel read by role (``pixelkit report`` on a ``pixel4t`` / ``netlist`` design).

The figures it shows are the role measurements (their references: tests/test_pixel4t.py, registered in
tests/figure_references.py); this checks the report's own contract on such a design: the sign-off and
the pixel section build, the verdict follows the team's exit rule (the quick profile runs the nominal
condition only, so the 85 degC dark-current spec is NOT RUN: exit 5, named), the pixel section's
figures are the sign-off's at the same condition (two code paths: verify's and the family's
experiment), and the report of the same pixel read from its netlist shows the same figures.
"""
import json

import pytest

from conftest import ROOT, run_cli

P4T = ROOT / "designs" / "pixel4t_gf180.toml"
NETLIST = ROOT / "designs" / "pixel4t_netlist.toml"


@pytest.fixture(scope="module")
def p4t_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("p4t") / "report"
    code, _stdout, err = run_cli("report", P4T, "--quick", "--out", out)   # with the HTML and the datasheet
    return code, json.loads((out / "summary.json").read_text()), out, err


def test_the_4t_report_builds_its_sections_and_says_what_it_did_not_run(p4t_report):
    code, s, out, err = p4t_report
    assert s["sections"] == {"signoff": "available", "pixel": "available"}, err[-2000:]
    assert code == 5 and s["verdict"]["verdict"] == "NOT MEASURED"
    assert [x["spec"] for x in s["verdict"]["not_measured"]] == ["dark_current_hot"] and not s["verdict"]["failing"]
    assert s["verdict"]["passing"] == 7 and s["verdict"]["specs"] == 8
    for f in ("index.html", "datasheet.html", "pixel_figures.csv", "pixel_lag_vs_tg.csv", "pixel_ladder.png",
              "pixel_transfer.png", "signoff_power.csv"):
        assert (out / f).exists(), f
    c = s["checked"]
    # verify's figure and the experiment's, at the nominal condition: the same decks
    assert c["pixel.conversion_gain_uV_per_e"]["value"] == pytest.approx(c["signoff.conversion_gain"]["value"], rel=1e-6)
    assert c["pixel.read_noise_e"]["value"] == pytest.approx(c["signoff.read_noise"]["value"], rel=1e-6)
    assert 0.5 < c["pixel.read_noise_e"]["value"] < 5


def test_the_netlist_pixel_reports_the_generators_figures(p4t_report, cli, tmp_path):
    _code, gen, _out, _err = p4t_report
    code, stdout, err = cli("report", NETLIST, "--quick", "--out", tmp_path / "r", "--json")
    s = json.loads(stdout)
    assert s["sections"] == {"signoff": "available", "pixel": "available"}, err[-2000:]
    for k in ("conversion_gain_uV_per_e", "full_well_e", "read_noise_e", "dark_current_e_per_s", "power_chip_W"):
        assert s["checked"][f"pixel.{k}"]["value"] == pytest.approx(gen["checked"][f"pixel.{k}"]["value"], rel=0.01), k
    assert "pixel.ppd_full_well_e" not in s["checked"]   # a designer's netlist has no closed forms


def test_a_gap_input_is_refused_for_a_pixel_read_by_role(cli, tmp_path):
    (tmp_path / "m.csv").write_text("x\n1\n")
    code, _out, err = cli("report", P4T, "--quick", "--out", tmp_path / "r", "--measured", tmp_path / "m.csv")
    assert code == 2 and "--measured" in err
