"""The suite's approx (tests/strict_approx.py) compares small quantities relatively."""
import pytest


def test_a_femtofarad_off_by_five_percent_fails_at_one_percent():
    assert not (1.05e-15 == pytest.approx(1e-15, rel=1e-2))
    assert 1.005e-15 == pytest.approx(1e-15, rel=1e-2)


def test_arrays_and_dicts_are_relative_too():
    assert not ([1e-16, 2.2e-16] == pytest.approx([1e-16, 2e-16], rel=0.05))
    assert not ({"i": 1.3e-18} == pytest.approx({"i": 1e-18}, rel=0.1))
    assert [1e-16, 0.0] == pytest.approx([1.01e-16, 0.0], rel=0.05)


def test_a_callers_abs_and_large_values_are_as_pytest_has_them():
    assert 1e-15 == pytest.approx(0.0)                 # zero keeps pytest's floor
    assert 3e-15 == pytest.approx(1e-15, abs=1e-14)    # the caller's abs stands
    assert 100.5 == pytest.approx(100, rel=1e-2)
    assert not (101.5 == pytest.approx(100, rel=1e-2))
