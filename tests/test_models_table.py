"""Table 3.2 and eq. 3.10 - 3.13 of the thesis [Thesis2019], computed by the analytic models.

Independent reference: SPICE. The c35_thesis stand-in's PD junction is *calibrated* on table 3.2
(its zero-bias capacitances are solved so that eq. 3.5 gives 26.54 / 7.38 fF at 2.5 V), so the
table's printed numbers are a round trip for the models, not a reference
(``test_c35_calibration_reproduces_table_3_2_unchanged`` only detects a change of the calibration).
What the models compute is checked against ngspice on the same diode card: both bare PDs
reset to the table's 2.5 V and discharged by a known current (``pd_pair_bench``); the charge
I t that moves V(pd) by a small step is the conversion gain, the charge that takes the PD
through the design's 1.5 V swing the full well.
"""
import json

import numpy as np
import pytest

from pixelkit.api import models as model_table   # the physics table at the SPICE SF gain
from pixelkit.constants import Q

# Reference numbers of the thesis (table 3.2 and the sizing text of chapter 3) and their tolerances.
THESIS = {"cg_primary": (6.03e-6, 0.02), "cg_secondary": (21.7e-6, 0.02),
          "fwc_primary": (248e3, 0.03), "fwc_secondary": (69e3, 0.03),
          "c_a": (8.18, 0.02), "c_c": (3.6, 0.02)}

#: Photocurrents of the SPICE discharge: each PD through its 1.5 V swing in ~45 us.
I_PD = {"primary": 1e-9, "secondary": 0.28e-9}
#: The small charge step (electrons): ~12 mV on either PD.
STEP_E = {"primary": 2000.0, "secondary": 550.0}


@pytest.fixture(scope="module")
def pd_discharge(ref_design):
    """V(pd) against the collected charge Q = I t of both bare PDs from the table's reset bias, in SPICE."""
    from pixelkit.circuits.testbench import pd_pair_bench
    from pixelkit.spice import simulate
    v0 = ref_design.tech.photodiode.reset_bias
    r = simulate(pd_pair_bench(ref_design, I_PD["primary"], I_PD["secondary"], 60e-6, v0, title="table_3_2"))
    return v0, {w: (I_PD[w] * np.asarray(r.time), np.asarray(r[n])) for w, n in (("primary", "pdp"), ("secondary", "pds"))}


def test_table_3_2_from_spice_charge_steps(ref_design, pd_discharge):
    """The models' table against SPICE on the same card: C_jdep(2.5 V) and CG = q / C_jdep from the
    drop of V(pd) under a ~12 mV charge step (0.3 %: C(V) changes by < 0.1 % over the step); the
    full well with C(V) as the charge that takes the PD from 2.5 V through the 1.5 V swing (0.1 %;
    measured 2e-6 / 7e-6),
    and the table's fixed-C full well (swing x C_jdep / q, its definition) from SPICE's C_jdep;
    C_C = C_jdep1 / C_jdep2 from the two steps; C_A from the thesis's printed PD sizes
    (15.1 x 13.55 / 5 x 5 um)."""
    from pixelkit.physics.subpixel import figures
    v0, runs = pd_discharge
    swing = ref_design.pixel.swing
    spice = {}
    for w, (q, v) in runs.items():
        assert 0 < v0 - v[0] < 1e-3 and v[-1] < v0 - swing, w     # from the .ic reset bias, through the swing
        dv = v0 - float(np.interp(STEP_E[w] * Q, q, v))
        c = STEP_E[w] * Q / dv
        q_fw = float(np.interp(-(v0 - swing), -v, q))       # V falls monotonically: interpolate on -V
        spice[w] = {"c_jdep_F": c, "cg_V_per_e": Q / c, "fwc_cv_e": q_fw / Q, "fwc_e": swing * c / Q}
    for w in ("primary", "secondary"):
        model = figures(ref_design, w)
        assert model["c_jdep_F"] == pytest.approx(spice[w]["c_jdep_F"], rel=0.003), w
        assert model["cg_V_per_e"] == pytest.approx(spice[w]["cg_V_per_e"], rel=0.003), w
        assert model["fwc_e"] == pytest.approx(spice[w]["fwc_e"], rel=0.003), w
        assert model["fwc_cv_e"] == pytest.approx(spice[w]["fwc_cv_e"], rel=0.001), w
        assert model["fwc_cv_e"] > model["fwc_e"]          # C rises as the PD discharges
    t = model_table(ref_design)
    assert t["c_c"] == pytest.approx(spice["primary"]["c_jdep_F"] / spice["secondary"]["c_jdep_F"], rel=0.005)
    assert t["c_a"] == pytest.approx(15.1 * 13.55 / (5.0 * 5.0), rel=1e-9)


def test_c35_calibration_reproduces_table_3_2_unchanged(ref_design):
    """A change detector, not a reference: the c35_thesis junction was solved to give table 3.2's
    capacitances, so this only says the calibration (and the reference design's PD sizes) still
    reproduce the printed table."""
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


def test_run_command_prints_the_checked_figures(ref_design, pd_discharge, experiment, cli):
    """``pixelkit run`` (the main job: models + simulation) as a command on the reference design: its
    model table against SPICE's charge steps (C_jdep 0.3 %, full well with C(V) 0.1 %, as above) and
    its simulation summary equal to the experiment that test_experiment checks against SPICE runs at
    the reported currents and the analytic charge chain."""
    from conftest import REF
    code, out, err = cli("run", REF, "--json")
    assert code == 0, err
    r = json.loads(out)
    v0, runs = pd_discharge
    for w, (q, v) in runs.items():
        c = STEP_E[w] * Q / (v0 - float(np.interp(STEP_E[w] * Q, q, v)))
        assert r["models"][w]["c_jdep_F"] == pytest.approx(c, rel=0.003), w
        assert r["models"][w]["fwc_cv_e"] * Q == pytest.approx(float(np.interp(-(v0 - ref_design.pixel.swing), -v, q)), rel=0.001), w
    for w, key in (("primary", "i_mid_A"), ("secondary", "i_5pct_A")):
        assert r["simulate"][w][key] == pytest.approx(experiment[w][key], rel=1e-9), w
        assert r["simulate"][w]["swing_V"] == pytest.approx(experiment[w]["swing_V"], rel=1e-9), w
