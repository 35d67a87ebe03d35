"""The SC AFE follows eq. 3.1; its residual is the op-amp's finite gain (derived in measure.afe)."""
from dataclasses import replace

import numpy as np
import pytest

from pixelkit.circuits.testbench import afe_bench
from pixelkit.physics.timing import GsTiming
from pixelkit.measure.afe import afe_output, eps, finite_gain_output, ideal_output
from pixelkit.spice import simulate_many

PAIRS = [(1.9 - dv, 1.9) for dv in np.linspace(0.0, 1.2, 7)]  # full pixel swing at the column


def _outputs(designs):
    nets = [afe_bench(d, PAIRS, title=f"afe{k}") for k, d in enumerate(designs)]
    res = simulate_many(nets)
    t = GsTiming(t_exp=0.0, t_row=1 / designs[0].afe.f_clk, rows=len(PAIRS), t_reset=0.0, t_tg=0.0,
                 t_gap=0.0, t_pre=0.0)
    return [np.array([afe_output(r, t, k) for k in range(len(PAIRS))]) for r in res]


def test_residual_is_the_finite_gain_error(ref_design):
    gains = (30.0, 100.0, 1000.0)
    designs = [replace(ref_design, afe=replace(ref_design.afe, gain=a)) for a in gains]
    dv = np.array([r - s for s, r in PAIRS])
    a = ref_design.afe
    for g, out in zip(gains, _outputs(designs)):
        slope, offset = np.polyfit(dv, out, 1)
        predicted = -(a.c11 / a.c13) / (1 + eps(a.c11, a.c13, g))
        # the gain error (1 + slope) is the predicted eps/(1+eps) within 5 % of itself
        assert 1 + slope == pytest.approx(1 + predicted, rel=0.05), g
        # the finite-gain model explains >= 95 % of the signal-dependent residual; what is
        # left is a constant offset (charge injection of the opening phase-1 switches)
        explained = finite_gain_output(a.vref, a.c11, a.c13, g, dv) - ideal_output(a.vref, a.c11, a.c13, dv)
        left = out - finite_gain_output(a.vref, a.c11, a.c13, g, dv)
        assert np.ptp(left) < 0.05 * np.ptp(explained) + 0.3e-3, g
        assert abs(np.mean(left)) < 0.03


def test_eq_3_1_over_the_full_input_range(ref_design):
    a = ref_design.afe
    dv = np.array([r - s for s, r in PAIRS])
    for design in (ref_design, replace(ref_design, afe=replace(a, opamp="ota"))):
        out = _outputs([design])[0]
        err = out - ideal_output(a.vref, a.c11, a.c13, dv)
        assert np.ptp(err) < 0.005 * np.ptp(dv)      # gain within 0.5 % over 1.2 V
        assert np.max(np.abs(err)) < 0.03             # offset: switch injection, tens of mV at most
