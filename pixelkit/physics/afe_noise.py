"""Temporal noise of the offset-compensated SC AFE (``circuits.afe``): kT/C and the op-amp.

Sampled-noise theory for the two-phase amplifier ([EnzTemes1996]: autozero and CDS). Voltages
are deviations from the nominal.

**What phase 2 makes of phase 1.** p1 opens and leaves x (op-amp inverting input,
through C12) and c (C13's far plate) floating with sampled values x1, c1; vm is left
too. In phase 2 the charge on x (C12 (x - vm)) and on vm are conserved, the loop
holds x at the op-amp's noise x2 = e_n (closed-loop filtered), and c joins out.
Charge conservation at x and vm gives (infinite gain, no parasitics)

    v_out = (x2 - x1) / beta + c1,    beta = C13 / (C11 + C13),

vm drops out (its charge is stored against C12: offset storage). Divided by the
gain C11/C13, the AFE input sees (x2 - x1)(C11 + C13)/C11 + c1 C13/C11.

**kT/C (switches).** The network at the instant p1 opens - x through Sfb to the
op-amp output in unity feedback, vm through Sref and c through Sc to Vref, C11 to the
held input - is second order in each switch. Solving its three nodes (switches
R_k, op-amp A0 / (1 + s A0 / 2 pi GBW)) gives, for any switch resistance and GBW
(R from 100 Ohm to 100 kOhm, A0 = 1000, GBW = 50 MHz: within 0.5 % of)

    var(c1 - x1 / beta) = kT [ 1 / (beta^2 C12) + 1 / (beta C13) ].

The C12 part in closed form: with vm held, x (1 + s R C12 + w_u / s) = v_R + (w_u / s) e,
so v_R (4kTR) gives the 2nd-order integral kT / C12 for any R and w_u = 2 pi GBW; the
C13 part is kT / C13 of c plus kT C11 / C13^2 of the charge Sref leaves on vm that
reaches c through C13. The formula of the previous version (2kT/C11 + kT/C12 +
kT C13/C11^2) had C11 sampled twice and C12 without the noise gain 1/beta: 4 kT/C for
equal capacitors where this gives 6 kT/C; ngspice (``tests/test_afe_noise.py``) 6.4.
In phase 2 the p2 switch (So) in the loop adds 4 k T R_on over the loop bandwidth,
about 3 % of the kT/C at the reference design: left out (no analytic R_on).

**Op-amp thermal noise** (white density e_w^2 = 4 k T R_n, ``afe.noise_r``). Phase 1:
the unity loop with the switch gives x (same equation) e w_u / (s^2 R C12 + s + w_u):
variance e_w^2 w_u / 4 = e_w^2 (pi/2) GBW, any R. Phase 2: x2 follows e through the
closed loop, one pole at beta GBW: e_w^2 (pi/2) beta GBW. The two samples are
uncorrelated for white noise (1/GBW << the phase time): wideband noise folds into
the sample, at the output

    var_thermal = e_w^2 (pi/2) GBW (1 + beta) / beta^2.

(The fast-switch limit: with R_on C comparable to 1/GBW the phase-1 part falls and
the phase-2 part rises by ~10 % each, in opposite directions; ngspice with the real
switches checks the sum.)

**Op-amp 1/f noise** (S = e_w^2 f_c / f, ``afe.noise_corner``). Correlated between the
autozero sample and the phase-2 sample, T = 1 / (2 f_clk) apart: the output is
(e filtered by H2 at t) - (e filtered by H1 at t - T), so

    var_1/f = (1/beta^2) int e_w^2 f_c / f  |H1 - H2 exp(-j 2 pi f T)|^2 df
            = (1/beta^2) int e_w^2 f_c / f [|H1|^2 + |H2|^2 - 2 Re(H1 H2*) cos 2 pi f T] df

with H1 = 1 / (1 + j f / GBW), H2 = 1 / (1 + j f / (beta GBW)); below 1/T this is the
CDS high-pass 2 - 2 cos(2 pi f T) and the 1/f noise cancels, above it the two
samples add. Integrated numerically (log grid).

With ``afe.opamp = "ota"`` these op-amp terms still use the macromodel's
``noise_r`` / ``noise_corner`` (the transistor OTA's own BSIM4 noise is in SPICE only).
"""
from __future__ import annotations

import numpy as np

from ..constants import K_B


def beta(design) -> float:
    a = design.afe
    return a.c13 / (a.c11 + a.c13)


def white_density(design) -> float:
    """Op-amp input-referred thermal PSD e_w^2 (V^2/Hz)."""
    return 4.0 * K_B * design.temperature * design.afe.noise_r


def half_period(design) -> float:
    """Time from the autozero sample (end of p1) to the amplified sample (end of p2)."""
    return 0.5 / design.afe.f_clk


def flicker_output(design, points_per_decade: int = 200) -> float:
    """Output variance (V^2) of the op-amp's 1/f noise through autozero + amplification."""
    a, b, t = design.afe, beta(design), half_period(design)
    if a.noise_r <= 0 or a.noise_corner <= 0:
        return 0.0
    lo, hi = 1e-4 / t, 1e4 * a.gbw
    f = np.logspace(np.log10(lo), np.log10(hi), int(points_per_decade * np.log10(hi / lo)) + 1)
    h1 = 1.0 / (1.0 + 1j * f / a.gbw)
    h2 = 1.0 / (1.0 + 1j * f / (b * a.gbw))
    w = np.abs(h1 - h2 * np.exp(-2j * np.pi * f * t)) ** 2
    s = white_density(design) * a.noise_corner / f
    return float(np.trapezoid(s * w, f)) / b ** 2


def output_variances(design) -> dict:
    """AFE output variances (V^2) by source."""
    a, kt, b = design.afe, K_B * design.temperature, beta(design)
    return {
        "afe_ktc_c12": kt / (b ** 2 * a.c12),
        "afe_ktc_c13": kt / (b * a.c13),
        "afe_opamp_thermal": white_density(design) * 0.5 * np.pi * a.gbw * (1.0 + b) / b ** 2,
        "afe_opamp_flicker": flicker_output(design),
    }


def input_variances(design) -> dict:
    """The same referred to the AFE input (the column), divided by the gain (C11/C13)^2."""
    g2 = (design.afe.c11 / design.afe.c13) ** 2
    return {k: v / g2 for k, v in output_variances(design).items()}
