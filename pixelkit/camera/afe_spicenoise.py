"""The SPICE side of the AFE noise: ngspice ``.noise`` at the two phase operating points.

An independent figure for ``physics.afe_noise``: the kit's AFE cell with its real CMOS
switches (BSIM4 channel noise, their capacitances, their on-resistance against the
op-amp's bandwidth) and the op-amp macromodel's noise elements, combined by
sampled-noise theory:

    var_out = var(c1 - x1/beta)  [phase-1 .noise, integrated: the sample p1 leaves]
            + var(out, phase 2)  [phase-2 .noise, integrated: the amplified sample]
            - the 1/f parts of both, counted instead as the correlated difference
              int S1 + S2 - 2 sqrt(S1 S2) cos(2 pi f T) df

S1, S2 are the op-amp's 1/f spectra in the two probes (spectrum with the 1/f corner
minus the spectrum without); T = 1 / (2 f_clk). The sqrt(S1 S2) form takes the two
transfers as in phase where the cosine matters (f << GBW).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..circuits.afenoise import phase1_deck, phase2_deck
from ..physics.afe_noise import half_period
from .spicenoise import run_noise


def _runs(design) -> tuple:
    return run_noise(phase1_deck(design)), run_noise(phase2_deck(design))


def afe_output_noise(design) -> dict:
    """AFE output variances (V^2) from ngspice: sampled (white + kT/C) and 1/f."""
    p1, p2 = _runs(design)
    white = design
    if design.afe.noise_corner > 0 and design.afe.noise_r > 0:
        white = replace(design, afe=replace(design.afe, noise_corner=0.0))
        w1, w2 = _runs(white)
    else:
        w1, w2 = p1, p2
    f = p1["f"]
    s1 = np.maximum(p1["psd"] - w1["psd"], 0.0)
    s2 = np.maximum(p2["psd"] - w2["psd"], 0.0)
    flicker = float(np.trapezoid(s1 + s2 - 2 * np.sqrt(s1 * s2) * np.cos(2 * np.pi * f * half_period(design)), f))
    sampled = w1["total_V"] ** 2 + w2["total_V"] ** 2
    return {"phase1_V2": w1["total_V"] ** 2, "phase2_V2": w2["total_V"] ** 2, "flicker_V2": flicker,
            "flicker_uncorrelated_V2": float(np.trapezoid(s1 + s2, f)), "total_V2": sampled + flicker}
