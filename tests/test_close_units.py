"""The parts of ``pixelkit close`` that need no simulation, against answers derived by hand or by the
binomial distribution summed directly (no SPICE, < 1 s)."""
import math

import numpy as np
import pytest

from pixelkit.close.step import Model, correct, optimise, restore


def test_max_min_step_and_its_conflict_certificate():
    """Two margins m1 = -0.1 + d and m2 = -0.1 - 2 d of one knob: no step raises both, the max-min point
    is d = 0 (t = -0.1), and the multipliers balance the gradients: lambda1 = 2 lambda2, lambda1 +
    lambda2 = 1, so each row pulls lambda |g| = 2/3 of the whole: equal shares, both named."""
    m = Model([("a", 1), ("b", 1)], np.array([-0.1, -0.1]), np.array([[1.0], [-2.0]]))
    st = restore(m, np.zeros(1), np.array([-1.0]), np.array([1.0]), 0.5)
    assert st.d[0] == pytest.approx(0.0, abs=1e-7) and st.t == pytest.approx(-0.1, abs=1e-7)
    assert set(st.multipliers) == {("a", 1), ("b", 1)}
    assert st.multipliers[("a", 1)] == pytest.approx(0.5, abs=1e-5)


def test_a_margin_held_by_a_knob_bound():
    """m = -0.5 + d with d <= 0.2 (the knob's max 0.2 above the start): t = -0.3 at the bound, one row
    and the bound named."""
    m = Model([("a", 1)], np.array([-0.5]), np.array([[1.0]]))
    st = restore(m, np.zeros(1), np.array([-1.0]), np.array([0.2]), 0.5)
    assert st.d[0] == pytest.approx(0.2, abs=1e-7) and st.t == pytest.approx(-0.3, abs=1e-7)
    assert list(st.multipliers) == [("a", 1)] and st.bounds == {0: "max"}


def test_restore_aims_at_the_cushion_and_no_further():
    """A reachable target: the shortest step that puts the margin at the cushion, not the radius."""
    m = Model([("a", 1)], np.array([-0.1]), np.array([[1.0]]))
    st = restore(m, np.zeros(1), np.array([-1.0]), np.array([1.0]), 0.5, cap=0.002)
    assert st.d[0] == pytest.approx(0.102, abs=1e-4)


def test_optimise_slides_along_the_active_margin():
    """min f = -x1 subject to 0.1 - x1 + x2 >= 0 and |d| <= 0.3: x2 at +0.3, x1 = 0.3 (the radius), the
    margin 0.1 left; with x2 held at its bound 0 the margin binds: x1 = 0.1."""
    m = Model([("a", 1)], np.array([0.1]), np.array([[-1.0, 1.0]]), 0.0, np.array([-1.0, 0.0]))
    st = optimise(m, np.zeros(2), np.array([-1.0, -1.0]), np.array([1.0, 1.0]), 0.3)
    assert st.d[0] == pytest.approx(0.3, abs=1e-6) and st.f == pytest.approx(-0.3, abs=1e-6)
    st = optimise(m, np.zeros(2), np.array([-1.0, -1.0]), np.array([1.0, 0.0]), 0.3)
    assert st.d[0] == pytest.approx(0.1, abs=1e-6) and st.d[1] == pytest.approx(0.0, abs=1e-6)


def test_second_order_correction_is_the_shortest_move_back():
    """The candidate at d = (0.3, 0) gave margin -0.06 (gradient (-1, 1)): the shortest e with
    -0.06 + (-e1 + e2) >= 0 is e = (-0.03, +0.03)."""
    m = Model([("a", 1)], np.array([0.1]), np.array([[-1.0, 1.0]]), 0.0, np.array([-1.0, 0.0]))
    d2 = correct(m, np.array([-0.06]), np.array([0.3, 0.0]), np.zeros(2), np.array([-1.0, -1.0]),
                 np.array([1.0, 1.0]), 0.5, 0.0)
    assert d2 == pytest.approx([0.27, 0.03], abs=1e-6)


def _binomial_tail(k: int, n: int, p: float) -> float:
    """P(X >= k), X ~ Binomial(n, p), summed term by term."""
    return sum(math.comb(n, i) * p ** i * (1 - p) ** (n - i) for i in range(k, n + 1))


@pytest.mark.parametrize("n,min_yield", [(200, 0.95), (200, 0.99), (50, 0.9), (20, 0.8)])
def test_passes_needed_against_the_binomial(n, min_yield):
    """The fewest passes k whose Clopper-Pearson lower bound (95 %) reaches min_yield: the smallest k with
    P(X >= k | p = min_yield) <= 2.5 % (the bound's definition), by direct summation."""
    from pixelkit.close.yields import passes_needed
    k = passes_needed(n, min_yield, 0.95)
    direct = next((j for j in range(n + 1) if _binomial_tail(j, n, min_yield) <= 0.025), None)
    assert k == direct


def test_too_few_samples_is_none_and_the_pass_probability_gives_the_assurance():
    from pixelkit.close.yields import ASSURANCE, passes_needed, required_pass_probability
    assert passes_needed(20, 0.99, 0.95) is None            # 20 of 20: lower bound 83 %
    k = passes_needed(200, 0.95, 0.95)
    p = required_pass_probability(200, k)
    assert _binomial_tail(k, 200, p) == pytest.approx(ASSURANCE, abs=1e-6)


def test_margins_in_units_of_the_limit():
    """5 % inside a min of 200 is +0.05; a max of 0.1 % with 0.3 % measured is -2 (200 % outside); a
    two-sided spec counts the nearer limit; a limit of 0 is measured against the other limit's size."""
    from types import SimpleNamespace as NS

    from pixelkit.close.margins import margin
    fig = NS(dim="1")
    lo = NS(lo=200.0, hi=None, typical=None, shown_unit="", fig=fig)
    hi = NS(lo=None, hi=0.001, typical=None, shown_unit="", fig=fig)
    two = NS(lo=4.0, hi=6.0, typical=5.0, shown_unit="", fig=fig)
    zero = NS(lo=0.0, hi=2.0, typical=None, shown_unit="", fig=fig)
    assert margin(lo, 210.0) == pytest.approx(0.05)
    assert margin(hi, 0.003) == pytest.approx(-2.0)
    assert margin(two, 5.8) == pytest.approx((6.0 - 5.8) / 6.0)
    assert margin(zero, 0.5) == pytest.approx(0.25)
    assert margin(lo, None) is None and margin(lo, float("nan")) is None
