"""``pytest.approx`` without its silent absolute floor.

pytest's approx accepts ``|actual - expected| <= max(rel |expected|, abs)`` with ``abs = 1e-12`` by
default: for a capacitance (1e-15 F), a dark current (1e-16 A) or a charge (1e-15 C) that floor is
a thousand times the value, so ``c == approx(c_model, rel=1e-3)`` passes for any c near zero - a
check that cannot fail. The suite installs this wrapper (tests/conftest.py) before any test module
imports approx: where the caller gives no ``abs`` and the relative tolerance of the smallest
non-zero expected value is below pytest's floor, the floor becomes that relative tolerance, so the
comparison is relative as written. An expectation of exactly zero keeps pytest's floor; a caller's
own ``abs`` is never changed.
"""
from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pytest

PYTEST_ABS = 1e-12
PYTEST_REL = 1e-6
_approx = pytest.approx


def _smallest_nonzero(expected) -> float | None:
    try:
        values = list(expected.values()) if isinstance(expected, Mapping) else expected
        a = np.abs(np.asarray(values, dtype=float)).ravel()
    except (TypeError, ValueError):
        return None
    a = a[np.isfinite(a) & (a > 0)]
    return float(a.min()) if a.size else None


def approx(expected, rel=None, abs=None, nan_ok=False):
    if abs is None:
        small = _smallest_nonzero(expected)
        r = PYTEST_REL if rel is None else rel
        if small is not None and r * small < PYTEST_ABS:
            return _approx(expected, rel=r, abs=r * small, nan_ok=nan_ok)
    return _approx(expected, rel=rel, abs=abs, nan_ok=nan_ok)


def install() -> None:
    pytest.approx = approx
