"""The 4T pinned-photodiode pixel (designs/pixel4t_gf180.toml) against derivations.

Independent paths: the closed forms of physics/ppd.py (the transfer ODE solved exactly, the full well
from the pinning voltage and the overflow diode), the closed-form FD capacitance of
families/pixel4t/model.py, a numerical ODE integration of the same transfer law (scipy), and the
time-domain read with a noisy reset drain. The SPICE figures come from rolepix (the decks verify runs).
"""
from dataclasses import replace

import numpy as np
import pytest

from conftest import PIXEL4T, ROOT

DESIGN = PIXEL4T


@pytest.fixture(scope="module")
def ppd(d4t):
    from pixelkit.circuits.pixel4t import ppd_model
    from pixelkit.families.pixel4t.design import tg_channel
    return ppd_model(d4t, tg_channel(d4t))


def test_ppd_charge_and_potential_are_inverse_and_full_well_is_c_vpin(ppd):
    from pixelkit.constants import Q
    for v in (-0.3, 0.0, 0.5, 0.99, 1.05):
        assert ppd.potential(ppd.charge(v)) == pytest.approx(v, abs=1e-9)
    # in the dark the well fills until the overflow diode returns the generation current:
    # V_F = -U_T ln(1 + I_gen / I_dif), i.e. C_PPD (V_pin + U_T ln(1 + I_gen / I_dif)) (up to the
    # exp(-V_pin / U_T) term): 4 % above C_PPD V_pin at this design's dark currents
    assert ppd.full_well() == pytest.approx(ppd.c * (ppd.v_pin + ppd.ut * np.log1p(ppd.i_gen / ppd.i_dif)), rel=1e-3)
    assert ppd.full_well() / (ppd.c * ppd.v_pin) - 1 == pytest.approx(0.043, abs=0.005)
    # a brighter light holds more: U_T ln(1 + I_ph / I_dif) per decade of light ([Pelamatti2015])
    gain = ppd.full_well(1e-9) - ppd.full_well(1e-10)
    assert gain == pytest.approx(ppd.c * ppd.ut * np.log(10), rel=1e-3)
    assert 10e3 < ppd.full_well() / Q < 30e3


def test_residual_closed_form_is_the_solution_of_the_transfer_law(ppd):
    """The exact solution against a numerical integration of dQ/dt = -I_TG(Q) with the full
    forward-minus-reverse law (what the SPICE B source evaluates), FD held far above the barrier."""
    from scipy.integrate import solve_ivp
    v_tg = 2.85
    q0 = 0.3 * ppd.full_well()
    sol = solve_ivp(lambda t, q: [-ppd.transfer_current(q[0], v_tg, 2.5)], (0, 5e-6), [q0], method="LSODA",
                    rtol=1e-10, atol=1e-24, dense_output=True)
    for t in (0.5e-6, 1e-6, 2e-6, 4e-6):
        assert sol.sol(t)[0] == pytest.approx(ppd.residual(q0, t, v_tg), rel=2e-3)


@pytest.fixture(scope="module")
def experiment(d4t):
    from pixelkit.families.pixel4t.experiment import run_pixel4t_experiment
    return run_pixel4t_experiment(d4t)


def test_transfer_and_lag_in_spice_follow_the_thermionic_closed_form(experiment):
    """The PPD's charge node in SPICE against Ppd.residual: the charge a 1 us transfer leaves at each TG
    level (none at the design's, thousands of electrons 0.5 - 0.8 V lower), and the charge through one
    long TG pulse where the emission time constant is ~1 us."""
    rows = experiment["lag_vs_tg"]
    assert rows[0]["left_spice_e"] < 1.0 and rows[0]["barrier_V"] < 0
    hold = [r for r in rows if r["left_model_e"] > 100]
    assert len(hold) >= 3
    for r in hold:
        assert r["left_spice_e"] == pytest.approx(r["left_model_e"], rel=0.01)
    tc = experiment["transfer_curve"]
    assert 0.2e-6 < tc["tau_s"] < 5e-6 and tc["q_start_e"] > 500
    err = np.abs(np.array(tc["spice_e"]) - np.array(tc["model_e"]))
    assert np.all(err <= np.maximum(0.02 * np.array(tc["model_e"]), 3.0))


def test_full_well_conversion_gain_dark_current_against_their_derivations(experiment):
    e = experiment
    pf = e["ppd_full_well"]
    assert pf["spice_e"] == pytest.approx(pf["model_e"], rel=5e-3)
    assert pf["dark_model_e"] == pytest.approx(pf["c_ppd_v_pin_e"], rel=5e-2)
    assert e["conversion_gain_uV_per_e"] == pytest.approx(e["conversion_gain_model_uV_per_e"], rel=0.05)
    assert e["dark_current_e_per_s"] == pytest.approx(e["dark_current_model_e_per_s"], rel=0.05)
    # the array's power: the loads' bias x supply x (1 + duty) (rolepix.power's estimate)
    assert e["power_chip_W"] == pytest.approx(e["power_estimate_W"], rel=0.05)
    # the output saturates before the PPD at bright light, after it in the dark: FD and the column swing
    assert pf["dark_model_e"] < e["full_well_e"] < pf["model_e"]
    assert abs(e["image_lag_pct"]) < 0.01 and e["image_lag_model_e"] < 1


def test_read_noise_is_a_few_electrons_where_the_fd_reset_noise_is_tens(experiment):
    """True CDS: the .noise figure holds the follower, load and S/H noise (a few e-), not FD's kT/C."""
    assert 0.5 < experiment["read_noise_e"] < 5.0
    assert experiment["fd_ktc_ncds_e"] > 5 * experiment["read_noise_e"]


def test_true_cds_cancels_a_reset_level_that_moves_every_frame(d4t):
    """A reset drain that lands every read on another level: the reset samples spread by mV, the CDS
    outputs (both samples of one reset) by less than a hundredth of that. (Measured 0.35 - 1.5 thousandths:
    the drain's noise is drawn anew each run - ngspice 39 does not hold TRNOISE to the deck's seed
    option - so a thousandth was a coin toss; a CDS that failed to cancel would leave ~1.)"""
    from pixelkit.rolepix.trnoise import fd_reset_check
    r = fd_reset_check(d4t)
    assert r["reset_sigma_V"] > 1e-3
    assert r["cds_sigma_V"] < 1e-2 * r["reset_sigma_V"]


def test_lag_at_the_output_with_a_barrier(d4t):
    """With a TG-edge barrier the CDS output of the dark frame after a bright one carries what the
    read's and the next shutter's transfers left (Ppd.residual over both), as a share of the bright signal."""
    from pixelkit.circuits.pixel4t import ppd_model
    from pixelkit.constants import Q
    from pixelkit.families.pixel4t import model
    from pixelkit.families.pixel4t.design import tg_channel
    from pixelkit.rolepix.signal import lag_run
    d = replace(d4t, ppd=replace(d4t.ppd, barrier=1.4))
    p = ppd_model(d, tg_channel(d))
    (dk, _s, b), _r, _n, lad = lag_run(d)
    closed = model.lag_electrons(p, lad["bright_e"] * Q, d.timing.t_tg, 3.3)
    assert closed["lag_e"] > 100
    assert (b[2] - dk[2]) / (b[1] - dk[1]) == pytest.approx(closed["lag_e"] / closed["signal_e"], rel=0.08)


@pytest.mark.slow
def test_transient_noise_agrees_with_the_noise_analysis(d4t):
    """The read noise in the time domain (each device's BSIM4 noise level as a TRNOISE source, 8 columns
    x 12 reads) brackets the .noise figure."""
    from pixelkit.rolepix.noise import noise
    from pixelkit.rolepix.trnoise import read_noise
    r = read_noise(d4t, columns=8, frames=12)
    lo, hi = r["interval_V"]
    assert lo <= noise(d4t)["sigma_V"] <= hi


def test_the_figures_docs_pixel4t_quotes_are_the_experiments(experiment):
    """docs/pixel4t.md marks each number it quotes from the experiment (``p4t:`` keys, docsite/figures.py), and so
    does every other page quoting the 4T's figures (docs/gap-diagnosis.md: its C_FD and kT/C)."""
    import sys
    sys.path.insert(0, str(ROOT))
    from docsite import figures

    def value(key):
        x = experiment
        for part in key.split("."):
            x = x[int(part)] if isinstance(x, list) else x[part]
        return float(x)
    pages = [p for p in figures.pages() if "<!--fig p4t:" in p.read_text()]
    assert ROOT / "docs" / "pixel4t.md" in pages
    bad, n = figures.check(None, pages, getters={"p4t": value})
    assert n >= 12
    assert not bad, bad


def test_the_exported_cds_deck_runs_in_raw_ngspice_and_reads_the_kit_signals(d4t, cli, tmp_path):
    """``pixelkit netlist`` of a role design writes its true-CDS deck; ``ngspice -b -r`` runs it alone (no
    kit code, another folder) and its held samples give the kit's own run of the same deck within
    0.1 mV: a dark pixel near 0, 1 ke- and 10 ke- at the conversion gain (independent path: raw ngspice)."""
    import os
    import subprocess
    from pixelkit.circuits.cds import timing_of
    from pixelkit.measure.cds import cds
    from pixelkit.rolepix.run import run
    from pixelkit.rolepix.export import CDS_EXPORT_E, export_benches
    from pixelkit.spice.raw import read_raw
    from pixelkit.spice.result import Result, vector_key
    deck = tmp_path / "out" / "cds.cir"
    code, _out, err = cli("netlist", DESIGN, "--bench", "cds", "--out", deck, "--json")
    assert code == 0, err
    code, _out, err = cli("netlist", DESIGN, "--bench", "nope", "--out", tmp_path / "x.cir", "--json")
    assert code == 2 and "cds" in err and "noise" in err
    where = tmp_path / "elsewhere"
    where.mkdir()
    p = subprocess.run(["ngspice", "-b", "-r", str(where / "out.raw"), str(deck)], cwd=where, capture_output=True,
                       text=True, timeout=300, env={**os.environ, "OMP_NUM_THREADS": "1"})
    assert (where / "out.raw").exists(), p.stdout[-2000:] + p.stderr[-2000:]
    data = read_raw(where / "out.raw")[-1]["data"]
    vec = {vector_key(k): np.real(v) for k, v in data.items()}
    raw = Result(np.real(vec.pop("time")), vec, {})
    net = export_benches(d4t)["cds"]()
    (kit,) = run([net], d4t)
    tm, fr = timing_of(d4t), net.meta["frames"]

    def outs(r):
        return [cds(r, tm, fr["exposures"], fr["starts"], k, 1) for k in range(len(CDS_EXPORT_E))]
    a, b = outs(raw), outs(kit)
    assert max(abs(x - y) for x, y in zip(a, b)) < 1e-4, (a, b)
    cg = (a[1] - a[0]) / CDS_EXPORT_E[1]
    assert 40e-6 < cg < 80e-6 and (a[2] - a[0]) / CDS_EXPORT_E[2] == pytest.approx(cg, rel=0.05)
