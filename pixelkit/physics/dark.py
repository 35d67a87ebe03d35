"""Dark current of each junction, each with the temperature law of its own model card.

The PD node and the storage node collect the reverse current of different
junctions, and each follows the law of the card SPICE uses for it:

- **the photodiode junction** (technology section ``photodiode``), by its
  ``dark_law``:

  - ``doubling``: I = (J_A A + J_P P) 2^((T - T_ref) / T_d) - the c35_thesis
    stand-in's stated law (no foundry card exists for it; 0.2 nA/cm2 and 7 K,
    typical of a non-pinned n-well PD between diffusion-limited, 4.5 K, and
    generation-limited, 9 K);
  - ``card``: the thermal (diffusion) saturation terms of a foundry diode card,
    with that card's own temperature law (SPICE's level-1 diode law):

        I = (is A + jsw P) (T / T_ref)^(xti / n) exp(eg / (n k) (1 / T_ref - 1 / T))

    (GF180MCU: ``diode_nw2ps_03v3``'s is, jsw, xti, eg, n; doubling every 4.2 K
    near room temperature). Its tunnelling terms (jtun, jtunsw) are left out: a
    reverse current that falls with temperature is not a thermal generation
    current (``techfit.pdcard`` measures the card and flags it).

  For both laws the kit writes the PD's .model card itself
  (``circuits.devices.photodiode_model``), with its saturation currents
  evaluated here at the deck temperature, so SPICE and the analytic models carry
  the same PD dark current; ``tests/test_dark.py`` checks the ``card`` formula
  against ngspice's own temperature scaling of the same card.

- **MOS source/drain diffusions** (the FD: TG drain and RST source; the PD node:
  EC and TG sources): BSIM4's junction law (tempmod 0),
  I_s = js A + jsw (P - W), scaled by exp([Eg(T0)/kT0 - Eg(T)/kT + xtis ln(T/T0)] / njs)
  from the models' tnom T0 (``diffusion_leakage``): x680 from 25 to 85 degC at
  2 V reverse bias (doubling every 6.4 K; the c35 stand-in's PD: x380, the GF180
  PD's thermal terms: x2e4). SPICE
  applies exactly this to every MOS diffusion; ``tests/test_dark.py`` checks it
  against ngspice from 25 to 85 degC.
"""
from __future__ import annotations

import numpy as np

from ..constants import K_B, Q


def dark_scale(temperature_K: float, pd) -> float:
    """Factor I(T) / I(T_ref) of the technology's photodiode junction (its ``dark_law``)."""
    t, t0 = temperature_K, pd.t_ref
    if getattr(pd, "dark_law", "doubling") == "card":
        f = (t / t0) ** (pd.dark_xti / pd.dark_n) * np.exp(pd.dark_eg / (pd.dark_n * K_B / Q) * (1.0 / t0 - 1.0 / t))
        return float(f) if np.ndim(f) == 0 else f      # an array of temperatures as the doubling law takes
    return 2.0 ** ((t - t0) / pd.dark_doubling)


def dark_current(area: float, perimeter: float, temperature_K: float, pd) -> float:
    """Dark current (A) of a PD junction of ``area``/``perimeter`` with the technology's ``pd`` section."""
    return (pd.dark_area * area + pd.dark_perimeter * perimeter) * dark_scale(temperature_K, pd)


def doubling_K(temperature_K: float, pd, dt: float = 1.0) -> float:
    """The temperature step that doubles the PD junction's dark current near ``temperature_K``."""
    r = dark_scale(temperature_K + dt / 2, pd) / dark_scale(temperature_K - dt / 2, pd)
    return float(dt * np.log(2.0) / np.log(r))


def bandgap(t: float) -> float:
    """Silicon bandgap (eV) at ``t`` (K), the BSIM4 expression."""
    return 1.16 - 7.02e-4 * t * t / (t + 1108.0)


def diffusion_leakage(w: float, tech, temperature_K: float) -> float:
    """Reverse current (A) of one MOS source/drain diffusion of width ``w``: BSIM4's law (module docstring)."""
    from .geometry import diffusion
    mos = tech.mos
    a, p = diffusion(w, mos.diff_ext)
    return (mos.js * a + mos.jsw * (p - w)) * mos_junction_scale(tech, temperature_K)


def mos_junction_scale(tech, temperature_K: float) -> float:
    """BSIM4's factor on a MOS diffusion's saturation current from the models' tnom to ``temperature_K``."""
    mos = tech.mos
    t0, t = mos.t_nom, temperature_K
    kq = K_B / Q
    arg = (bandgap(t0) / (kq * t0) - bandgap(t) / (kq * t) + mos.xtis * np.log(t / t0)) / mos.njs
    return float(np.exp(arg))
