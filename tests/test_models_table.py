"""Table 3.2 and eq. 3.10 - 3.13 of the thesis [Thesis2019], computed by the analytic models."""
import json

import pytest

from pixelkit.api import models as model_table   # the physics table at the SPICE SF gain

# Reference numbers of the thesis (table 3.2 and the sizing text of chapter 3) and their tolerances.
THESIS = {"cg_primary": (6.03e-6, 0.02), "cg_secondary": (21.7e-6, 0.02),
          "fwc_primary": (248e3, 0.03), "fwc_secondary": (69e3, 0.03),
          "c_a": (8.18, 0.02), "c_c": (3.6, 0.02)}


def test_table_3_2_and_eq_3_10_to_3_13(ref_design):
    t = model_table(ref_design)
    got = {"cg_primary": t["primary"]["cg_V_per_e"], "cg_secondary": t["secondary"]["cg_V_per_e"],
           "fwc_primary": t["primary"]["fwc_e"], "fwc_secondary": t["secondary"]["fwc_e"],
           "c_a": t["c_a"], "c_c": t["c_c"]}
    for key, (ref, tol) in THESIS.items():
        assert got[key] == pytest.approx(ref, rel=tol), key


def test_sidewall_dominates_as_the_thesis_says_of_c35(ref_design):
    pd = ref_design.tech.photodiode
    v = pd.reset_bias
    for sub in (ref_design.primary, ref_design.secondary):
        bottom = pd.cj * sub.area / (1 + v / pd.pb) ** pd.mj
        side = pd.cjsw * sub.perimeter / (1 + v / pd.pbsw) ** pd.mjsw
        assert side > bottom


def test_capacitance_rises_as_the_pd_discharges(ref_design):
    from pixelkit.physics.subpixel import pd_node
    node = pd_node(ref_design, "secondary")
    assert node.capacitance(0.5) > node.capacitance(1.5) > node.capacitance(2.5)


def test_models_json_keys(cli):
    code, out, err = cli("models", "designs/dual_pixel_revA.toml", "--json")
    assert code == 0, err
    data = json.loads(out)
    for sub in ("primary", "secondary"):
        assert {"c_jdep_F", "cg_V_per_e", "fwc_e", "area_m2", "perimeter_m"} <= set(data[sub])
    assert data["c_a"] == pytest.approx(8.18, rel=0.02) and data["c_c"] == pytest.approx(3.6, rel=0.02)
    # PD-referred and output-referred CG side by side at the design's own reset bias (2.0 V);
    # the output-referred one is checked against a SPICE charge step in test_noise.py
    for sub in ("primary", "secondary"):
        r = data[sub]["at_reset"]
        assert r["v_bias_V"] == pytest.approx(2.0)
        assert r["cg_out_V_per_e"] < r["cg_pd_V_per_e"] < data[sub]["cg_V_per_e"] * 1.0001
