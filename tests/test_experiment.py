"""The thesis's [Thesis2019] simulation experiment (fig. A.1 - A.3) and the model-vs-SPICE cross-check."""
import json

import pytest

from pixelkit.circuits.testbench import dual_pixel_bench, timings
from pixelkit.spice import simulate_many


#: Pinned figures of the reference design (ngspice 39, c35_thesis, revA timing), measured
#: with ``pixelkit simulate designs/dual_pixel_revA.toml --json``. Tolerance 3 %: the
#: interpolation between sweep points is good to 0.2 % of swing (the SPICE run at the reported
#: currents below), so a move beyond 3 % is a change of the bench, its timing or the models
#: that must be looked at and re-pinned, not noise.
# Re-checked (issue 27) against the independent derivation below: -3.1 % / -0.1 %. The thesis's read
# (designs/dual_pixel_revA_thesis_read.toml, 400 nA) gives 1.1012 nA / 37.27 pA: +6 %, the swing the
# SF keeps at 400 nA, which the derivation follows (-3.3 % / -0.6 % there).
PINNED = {"i_mid_A": 1.0351e-9, "i_5pct_A": 35.08e-12}
PIN_REL = 0.03


def test_ratio_of_target_currents_within_thesis_band(experiment):
    """Published reference: the thesis's 1400 pA / 52 pA = 26.9; the issue allows 22 - 36
    (the kit's c35_thesis stand-in is calibrated on the PD junction, not on the SF chain)."""
    assert 22 <= experiment["ratio"] <= 36
    assert experiment["ratio"] == pytest.approx(experiment["primary"]["i_mid_A"]
                                                / experiment["secondary"]["i_5pct_A"])


def test_i_mid_and_i_5pct_unchanged(experiment):
    """Change detector: i_mid and i_5pct against the pinned values within 3 %."""
    assert experiment["primary"]["i_mid_A"] == pytest.approx(PINNED["i_mid_A"], rel=PIN_REL)
    assert experiment["secondary"]["i_5pct_A"] == pytest.approx(PINNED["i_5pct_A"], rel=PIN_REL)


def test_spice_at_the_reported_currents_lands_on_the_targets(ref_design, experiment):
    """Independent reference: SPICE runs of the dual-pixel bench at the reported i_mid / i_5pct
    (not the sweep they were interpolated from), a dark run and a run at the sweep's top
    current (the PD node taken through the design swing: the column clips at ground), with the
    column read here at the sample instants: (signal - dark) / (top - dark) must be 0.5 within
    0.2 % of swing and 0.05 within 1 % of itself."""
    d = ref_design
    i_p, i_s = experiment["primary"]["i_mid_A"], experiment["secondary"]["i_5pct_A"]
    top_p, top_s = max(experiment["primary"]["sweep_A"]), max(experiment["secondary"]["sweep_A"])
    runs = simulate_many([dual_pixel_bench(d, 0.0, 0.0, title="pin_dark"),
                          dual_pixel_bench(d, i_p, i_s, title="pin_at_targets"),
                          dual_pixel_bench(d, top_p, top_s, title="pin_top")])
    tm = timings(d, d.experiment.t_window)
    frac = {}
    for which, col in (("primary", "col_p"), ("secondary", "col_s0")):
        t = tm[which]
        dark, at, top = (float(r.at(col, t.t_reset_level(0)) - r.at(col, t.t_signal(0))) for r in runs)
        frac[which] = (at - dark) / (top - dark)
    assert frac["primary"] == pytest.approx(d.experiment.mid_fraction, abs=0.002)
    assert frac["secondary"] == pytest.approx(d.experiment.low_fraction, rel=0.01)


def test_three_secondary_subpixels_agree(experiment):
    """Reference: symmetry; the three secondaries are identical circuits at the same current."""
    assert experiment["secondary"]["subpixel_spread_V"] < 1e-3


def test_fig_a1_pds_discharge_together(experiment):
    """Independent reference: SPICE bare PDs driven in the analytic C_C ratio (fig. A.1)."""
    assert experiment["fig_a1"]["max_diff_frac"] <= 0.02


def test_analytic_model_vs_spice_within_5_percent(experiment):
    """Independent reference: SPICE's V(pd) against the analytic C(V) discharge (other level)."""
    assert experiment["model_vs_spice"]["primary"] <= 0.05
    assert experiment["model_vs_spice"]["secondary"] <= 0.05


def test_simulate_json(cli, experiment):
    """The command prints the experiment's figures (checked above against SPICE runs at the
    reported currents and the pinned values)."""
    code, out, err = cli("simulate", "designs/dual_pixel_revA.toml", "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["t_window_s"] == experiment["t_window_s"]
    assert d["primary"]["i_mid_A"] == pytest.approx(experiment["primary"]["i_mid_A"], rel=1e-9)
    assert d["secondary"]["i_5pct_A"] == pytest.approx(experiment["secondary"]["i_5pct_A"], rel=1e-9)
    assert 0 <= d["model_vs_spice"]["max_err_frac"] <= 0.05


def test_shared_backend_gives_the_same_experiment(ref_design, experiment):
    """Reference: the same decks in libngspice (PySpice shared) instead of ngspice -b."""
    from pixelkit.experiments.thesis import run_experiment
    shared = run_experiment(ref_design, backend="shared")
    assert shared["ratio"] == pytest.approx(experiment["ratio"], rel=1e-3)


def test_target_currents_against_the_charge_chain_derivation(ref_design, experiment):
    """Independent path for the pinned i_mid / i_5pct: the analytic charge chain, not the sweep.
    Electrons are added in small steps, each raising the output by the chain's gain at the node's
    present bias (physics.fd.transfer: charge sharing, TG turn-off, RS turn-on; the SF gain from
    its DC sweep) and lowering the shared PD / FD node by Q / C_transfer there, until the output
    reaches the target fraction of SPICE's swing; i = N q / t_window. Measured: -3.1 % / -0.1 %
    (reference design, 1 uA load: 1.0351 nA / 35.08 pA in SPICE), -3.3 % / -0.6 % (the thesis's read at 400 nA):
    the primary's remainder is the SF gain taken as constant over half the swing."""
    from pixelkit.camera.spicenoise import sf_gain
    from pixelkit.physics import fd
    from pixelkit.techfit.ekv import models_for
    d, q = ref_design, 1.602176634e-19
    a, models = sf_gain(d), models_for(d)
    for which, key, frac, step, rel in (("primary", "i_mid_A", d.experiment.mid_fraction, 200.0, 0.05),
                                         ("secondary", "i_5pct_A", d.experiment.low_fraction, 50.0, 0.02)):
        target, v, out, n = frac * experiment[which]["swing_V"], d.pixel.v_pd_reset, 0.0, 0.0
        while out < target:
            t = fd.transfer(d, which, a, models, v)
            out, v, n = out + a * t["cg_fd_V_per_e"] * step, v - t["cg_transfer_V_per_e"] * step, n + step
        assert n * q / d.experiment.t_window == pytest.approx(experiment[which][key], rel=rel), which


def test_pedestal_is_the_fd_step_through_the_follower(ref_design, experiment):
    """The experiment's pedestal (the double-sampled column signal at zero photocurrent) against the
    FD node itself: FD's level at the reset sample minus at the signal sample (the dark transfer's TG
    and RS kicks that the second reset removes) times the follower's small-signal gain from two
    operating points of the read chain around that level (``sf_gain``, no transient): 1 %
    (measured 1e-5)."""
    from pixelkit.camera.spicenoise import sf_gain
    from pixelkit.spice import simulate
    d = ref_design
    tm = timings(d, d.experiment.t_window)
    r = simulate(dual_pixel_bench(d, 0.0, 0.0, title="pedestal_fd"))
    for kind, fd_node in (("primary", "x1.xp.fd"), ("secondary", "x1.xs0.fd")):
        t = tm[kind]
        v_sig, v_rst = float(r.at(fd_node, t.t_signal(0))), float(r.at(fd_node, t.t_reset_level(0)))
        assert v_rst - v_sig > 0.01, kind                      # a real step, not noise
        want = sf_gain(d, 0.5 * (v_sig + v_rst)) * (v_rst - v_sig)
        assert experiment[kind]["pedestal_V"] == pytest.approx(want, rel=0.01), kind
