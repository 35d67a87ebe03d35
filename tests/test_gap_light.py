"""Readout light on the SC AFE: full-chain SPICE with a junction current as a circuit element vs the derivation.

Independent path: the derivation written in ``pixelkit/gap/nominal.py`` (charge
balance of the AFE's vm island: a current I on vm from p1 opening to the output
sample leaves Q = I t_float, t_float = s2_off - s1_off + t_no (the row read), and moves the output by
+I t_float / C13) against ngspice running the reference design's full chain
(dual pixel, column loads, S1X/S2X, one SC AFE per column) with a current
source on each AFE's vm node (``circuit_edits.vm_current``), at three signal
levels of the secondary and one of the primary, against the same deck with the
sources at zero. Nothing here uses the surrogate's measured table.
"""
import numpy as np
import pytest

from pixelkit.circuits.testbench import dual_pixel_bench, timings
from pixelkit.gap import circuit_edits as ce
from pixelkit.gap.nominal import _q_max, t_float
from pixelkit.measure.afe import eps
from pixelkit.spice import simulate_many

I_S = 4e-9          # A on each secondary AFE: 4 - 8 mV at the output
I_P = 2e-9          # A on the primary's AFE
FRACS = (0.083, 0.19, 0.60)   # of the secondary's swing: ~0.12, ~0.23, ~0.42 V of signal


def _deck(d, scale, title):
    t_w = d.experiment.t_window
    qs = tuple(f * _q_max(d, "secondary") / t_w for f in FRACS)
    net = ce.specialise(dual_pixel_bench(d, 0.083 * _q_max(d, "primary") / t_w, qs, with_afe=True, title=title),
                        d.secondary_per_pixel)
    net = ce.add_to_subckt(net, "scafe_col_p", ce.vm_current(d, "primary", scale * I_P))
    for k in range(3):
        net = ce.add_to_subckt(net, f"scafe_col_s{k}", ce.vm_current(d, "secondary", scale * I_S))
    return net


@pytest.fixture(scope="module")
def runs(thesis_read_design):
    return simulate_many([_deck(thesis_read_design, 0.0, "lt_zero"), _deck(thesis_read_design, 1.0, "lt_on")])


@pytest.fixture(scope="module")
def former_read(thesis_read_design):
    """The reference design as it was before its read was retimed for settling (400 nA load, the kit's
    default read: S1 0.1 - 0.4, S2 0.6 - 0.9 of the row): its 200 ns open-loop gap lets the output of a
    0.42 V signal reach the clamp; the reference design's own read leaves 100 ns, and the output stays
    below the supply (docs/timing-and-settling.md)."""
    from dataclasses import replace
    from pixelkit.readout_timing import Timing
    d = replace(thesis_read_design, primary=replace(thesis_read_design.primary, timing=Timing()),
                secondary=replace(thesis_read_design.secondary, timing=Timing()),
                pixel=replace(thesis_read_design.pixel, sf_bias=400e-9))
    return d, simulate_many([_deck(d, 0.0, "lt_zero_former"), _deck(d, 1.0, "lt_on_former")])


def _shift(runs, d, col, arr):
    t = timings(d, d.experiment.t_window)[arr]
    ts = t.t_reset_level(0)
    nodes = {"vm": f"xafe_{col}.vm", "x": f"xafe_{col}.x", "in": f"in_{col}", "out": f"out_{col}"}
    dv = {k: float(runs[1].at(n, ts) - runs[0].at(n, ts)) for k, n in nodes.items()}
    t_a = t.s1_window(0)[1] - d.afe.nonoverlap          # p1 opens: the island's charge is set with in = Vsig
    dv["sig"] = float(runs[1].at(col, t_a) - runs[0].at(col, t_a))
    tt = np.linspace(t_a, t.s2_window(0)[0] - d.afe.nonoverlap, 80)   # the open-loop gap: p1 opens -> p2 closes
    gap_max = max(float(runs[1].at(nodes["out"], x)) for x in tt)
    return dv, gap_max, t


def test_vm_island_charge_is_current_times_float_time(runs, thesis_read_design):
    """Charge conservation on the vm island at every signal level, clamped or not: dQ = -I t_float."""
    a = thesis_read_design.afe
    for col, arr, i in (("col_p", "primary", I_P), *((f"col_s{k}", "secondary", I_S) for k in range(3))):
        dv, _, t = _shift(runs, thesis_read_design, col, arr)
        dq = a.c11 * (dv["vm"] - dv["in"]) + a.c12 * (dv["vm"] - dv["x"]) + a.c13 * (dv["vm"] - dv["out"])
        # 3 %: the switch opens over a 10 ns edge (1 - 2 % of t_float) and ngspice's charge tolerance
        assert dq == pytest.approx(-i * t_float(thesis_read_design, 1.0 / t.t_row, arr), rel=0.03), col


def test_output_shift_is_charge_over_c13_below_the_clamp(runs, thesis_read_design):
    """Where the op-amp's open-loop output stays below the supply in the p1-p2 gap, the island's charge
    balance gives dVout = I t_float / C13 + (C11 / C13) (dVsig - dVrst): the light's charge over C13, plus
    the AFE's own response to the levels it holds on C11 (in at p1 opening, in at the sample; the in node's
    floating charge moves the reset level a little), both measured on the nodes of the same deck."""
    a = thesis_read_design.afe
    k = eps(a.c11, a.c13, a.gain)
    checked = 0
    for col, arr, i in (("col_p", "primary", I_P), ("col_s0", "secondary", I_S), ("col_s1", "secondary", I_S)):
        dv, gap_max, t = _shift(runs, thesis_read_design, col, arr)
        assert gap_max < thesis_read_design.tech.supply, col          # these levels do not reach the clamp
        want = (i * t_float(thesis_read_design, 1.0 / t.t_row, arr) / a.c13 + a.c11 / a.c13 * (dv["sig"] - dv["in"])) / (1 + k)
        # 3 % + 0.05 mV: the island charge's 3 % above, and ngspice's tolerance on two decks
        assert dv["out"] == pytest.approx(want, rel=0.03, abs=0.05e-3), col
        checked += 1
    assert checked == 3


def test_clamp_departure_is_the_charge_put_on_x(former_read):
    """At ~0.42 V of signal the open-loop output passes the supply and the off feedback switch's junction
    puts charge dQx on x's island; the output then departs from I t_float / C13 by
    -(C11 + C12 + C13) dQx / (C12 C13) (charge balance with x at virtual ground; plus the held levels' term
    of the test above), here turning it negative: the sign change the virtual silicon showed."""
    thesis_read_design, runs = former_read
    a = thesis_read_design.afe
    dv, gap_max, t = _shift(runs, thesis_read_design, "col_s2", "secondary")
    assert gap_max > thesis_read_design.tech.supply + 0.3
    dqx = a.c12 * (dv["x"] - dv["vm"])
    lin = I_S * t_float(thesis_read_design, 1.0 / t.t_row, "secondary") / a.c13
    departure = dv["out"] - lin
    assert departure < -lin                                    # the response changes sign
    want = -(a.c11 + a.c12 + a.c13) * dqx / (a.c12 * a.c13) + a.c11 / a.c13 * (dv["sig"] - dv["in"])
    assert departure == pytest.approx(want, rel=0.03)


def test_table_interpolation_error_is_a_quadratics_midpoint_error():
    """The readout-light table's stated interpolation error (``nominal.table_interp_error`` x
    ``INTERP_AT_SPACING``) against its derivation: on a table of x^2 + 3 y^2 (spacings h and k), a node's
    leave-one-out error along x is h^2 and along y 3 k^2, and a bilinear table's largest error in a cell is at
    its middle: (h / 2)^2 along x, 3 (k / 2)^2 along y; the edges (no neighbour on one side) carry the other
    axis's only; a linear table has none. Where the response steps between two nodes the error is the step's
    half at both nodes."""
    from pixelkit.gap.nominal import INTERP_AT_SPACING, table_interp_error
    h, k = 0.1, 0.5
    x, y = np.arange(6) * h, np.arange(5) * k
    err = table_interp_error(x, y, x[:, None] ** 2 + 3 * y[None, :] ** 2) * INTERP_AT_SPACING
    mid_x = (h / 2) ** 2     # x^2: the straight line over a cell misses it by (h / 2)^2 at the middle
    mid_y = 3 * (k / 2) ** 2
    assert err[1:-1, 1:-1] == pytest.approx(np.full((4, 3), max(mid_x, mid_y)), rel=1e-9)
    assert err[0, 1:-1] == pytest.approx(np.full(3, mid_y), rel=1e-9)
    assert err[1:-1, 0] == pytest.approx(np.full(4, mid_x), rel=1e-9)
    assert err[0, 0] == 0.0
    assert np.max(table_interp_error(x, y, 2 * x[:, None] - y[None, :])) < 1e-12
    step = np.where(x >= 0.25, 1.0, 0.0)[:, None] * np.ones(y.size)
    assert table_interp_error(x, y, step)[2:4, :] == pytest.approx(np.full((2, 5), 0.5), rel=1e-9)
