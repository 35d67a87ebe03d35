"""Shot noise and kTC (reset) noise."""
from __future__ import annotations

import numpy as np

from ..constants import K_B, Q


def ktc_voltage(c: float, temperature_K: float) -> float:
    """RMS reset noise sqrt(kT/C) in V (hard reset)."""
    return float(np.sqrt(K_B * temperature_K / c))


def ktc_electrons(c: float, temperature_K: float) -> float:
    """RMS reset noise in electrons: sqrt(kTC)/q."""
    return float(np.sqrt(K_B * temperature_K * c) / Q)


def shot_electrons(n_electrons):
    """Poisson shot noise of a mean of ``n_electrons`` (RMS electrons)."""
    return np.sqrt(np.asarray(n_electrons, dtype=float))
