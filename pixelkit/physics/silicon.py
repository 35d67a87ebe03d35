"""Optical constants of crystalline silicon: absorption coefficient and refractive index by wavelength.

Published data, cited: [Green2008] table 1 (intrinsic silicon at 300 K with temperature
coefficients), kept as ``data/silicon_green2008.csv``. Between the tabulated 10 nm points the
absorption coefficient is interpolated in log (it spans eight decades, 250 - 1200 nm), the index
linearly; outside the table the call is refused (no extrapolation of an absorption edge).
Temperature: x(T) = x(300 K) (T / 300 K)^b with b = c x 300 K, the table's coefficients
([Green2008] eq. 2), so silicon absorbs more in the near infrared when hot (x1.5 at 1000 nm,
85 degC).

The generation a photon flux leaves in silicon follows from alpha: a plane wave entering with power
P decays as exp(-alpha z), so a slab [z0, z1] absorbs P (exp(-alpha z0) - exp(-alpha z1)).
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

DATA = Path(__file__).parent / "data" / "silicon_green2008.csv"
T0 = 300.0
COLUMNS = ["wavelength_nm", "alpha_per_cm", "n", "c_n_1e-4_per_K", "c_alpha_1e-4_per_K"]


@lru_cache(maxsize=1)
def table() -> dict:
    """The table as arrays: wavelength_m, alpha_per_m, n, b_n, b_alpha (the exponents at 300 K)."""
    lines = [ln for ln in DATA.read_text().splitlines() if ln.strip() and not ln.startswith("#")]
    head = lines[0].split(",")
    if head != COLUMNS:
        raise ValueError(f"{DATA.name}: columns {head}, expected {COLUMNS}")
    rows = np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])
    return {"wavelength_m": rows[:, 0] * 1e-9, "alpha_per_m": rows[:, 1] * 100.0, "n": rows[:, 2],
            "b_n": rows[:, 3] * 1e-4 * T0, "b_alpha": rows[:, 4] * 1e-4 * T0}


def _check(wl):
    t = table()
    lo, hi = t["wavelength_m"][0], t["wavelength_m"][-1]
    if np.any(wl < lo * (1 - 1e-9)) or np.any(wl > hi * (1 + 1e-9)):
        raise ValueError(f"wavelength outside the silicon table ({lo * 1e9:.0f} - {hi * 1e9:.0f} nm)")


def alpha(wavelength_m, temperature_K: float = T0):
    """Absorption coefficient (1/m) at ``wavelength_m`` and ``temperature_K``."""
    wl = np.asarray(wavelength_m, float)
    _check(wl)
    t = table()
    a = np.exp(np.interp(wl, t["wavelength_m"], np.log(t["alpha_per_m"])))
    b = np.interp(wl, t["wavelength_m"], t["b_alpha"])
    return a * (temperature_K / T0) ** b


def index(wavelength_m, temperature_K: float = T0):
    """Complex refractive index n + i k (k = alpha lambda / 4 pi)."""
    wl = np.asarray(wavelength_m, float)
    _check(wl)
    t = table()
    n = np.interp(wl, t["wavelength_m"], t["n"]) * (temperature_K / T0) ** np.interp(wl, t["wavelength_m"], t["b_n"])
    return n + 1j * alpha(wl, temperature_K) * wl / (4 * np.pi)


def absorbed(alpha_per_m, z0, z1):
    """Fraction of the power entering at depth 0 absorbed between depths ``z0`` and ``z1`` (m)."""
    return np.exp(-alpha_per_m * z0) - np.exp(-alpha_per_m * z1)
