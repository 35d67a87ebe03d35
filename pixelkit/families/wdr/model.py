"""Closed-form model of the WDR pixel: node charge, knee, t_c, dynamic range.

Node. During integration the photocurrent discharges C_int in parallel with the
PD junction (through the closed integration switches) and the diffusions of the
switches on both nodes and the comparator's input gate. The charge between two
voltages is

    dQ(V_a -> V_b) = C_lin (V_a - V_b) + Q_pd(V_a) - Q_pd(V_b)

with C_lin = C_int + the (bias-independent, estimated) MOS parasitics and Q_pd the
depletion charge of the PD junction ([Thesis2019] eq. 3.5, ``physics.junction``).

Exposure. A constant current I reaches V0 at t = dQ(V_start -> V0) / I. The
comparator acts when that is shorter than the frame, 2^N T:

    I_knee = dQ(V_start -> V0) / (2^N T)          (the knee V0 puts)
    I_max  = dQ(V_start -> V0) / T                (flip at T: the brightest coded)
    I      = dQ(V_start -> V0) / t_c              (high light)
    I      = dQ(V_start -> V3) / (2^N T)          (low light, signal 3)

so I_max / I_knee = 2^N exactly: +20 log10(2^N) dB (48 dB for N = 8).
Low light ends at the noise floor v_n of the node, derived (``noise``) from its
parts: the reset (kT / C of the node, a hard reset: the switch's gate is above
its drain by more than V_T), the sample taken when the exposure switch opens
(kT / C_int), the shot noise of the dark charge collected over the whole
exposure 2^N T (the PD junction and the five switch diffusions on the node,
each with its own law, ``physics.dark``) and the readout after the pixel
(``noise.v_read``, not in the circuit: an input):
CVDR = 20 log10((V_start - V0) / v_n) and I_min = C(V_start) v_n / (2^N T), so

    DR = 20 log10(I_max / I_min) ~ CVDR + 20 log10(2^N)

(equal when C is constant over the swing: the paper's eq. (1)).
"""
from __future__ import annotations

import math

from ...physics.geometry import diffusion
from ...constants import K_B
from ...physics.junction import Junction, capacitance, charge


def _pd_junction(tech) -> Junction:
    p = tech.photodiode
    return Junction(p.cj, p.mj, p.pb, p.cjsw, p.mjsw, p.pbsw)


def c_linear(design) -> float:
    """C_int plus the MOS parasitics on the integration node and the PD (estimate, zero bias).

    Diffusions: Mrst and Mexp on int, Mab and Men on pd, Men/Mexp's shared node;
    gates: the channels of the two closed integration switches (Cox W L each, to
    their gates at the supply) and the comparator's input device (Cox W L).
    """
    mos, px, cp = design.tech.mos, design.pixel, design.comparator
    a, p = diffusion(px.sw_w, mos.diff_ext)
    c_diff = a * mos.cj + (p - px.sw_w) * mos.cjsw + px.sw_w * mos.cjswg
    return px.c_int + 5 * c_diff + mos.cox * (2 * px.sw_w * px.sw_l + cp.in_w * cp.in_l)


def delta_q(design, v_a, v_b):
    """Charge (C) that takes the node from ``v_a`` down to ``v_b``."""
    px = design.pixel
    j = _pd_junction(design.tech)
    return (c_linear(design) * (v_a - v_b) + charge(v_a, px.area, px.perimeter, j)
            - charge(v_b, px.area, px.perimeter, j))


def node_capacitance(design, v) -> float:
    px = design.pixel
    return c_linear(design) + float(capacitance(v, px.area, px.perimeter, _pd_junction(design.tech)))


def dark_current(design, temperature_K: float | None = None) -> float:
    """The node's dark current (A): the PD junction plus the five switch diffusions (``c_linear``)."""
    from ...physics.dark import dark_current as pd_dark
    from ...physics.dark import diffusion_leakage
    px, t = design.pixel, (design.temperature if temperature_K is None else temperature_K)
    return pd_dark(px.area, px.perimeter, t, design.tech.photodiode) + 5 * diffusion_leakage(px.sw_w, design.tech, t)


def noise(design, v_start: float | None = None) -> dict:
    """The node's noise floor by part (V^2) and in total (V rms): see the module docstring."""
    from ...constants import Q
    px, cd = design.pixel, design.coding
    v_start = px.v_reset if v_start is None else v_start
    c = node_capacitance(design, v_start)
    kt = K_B * design.temperature
    n_dark = dark_current(design) * (2 ** cd.steps) * cd.t_unit / Q
    parts = {"reset_V2": kt / c, "exposure_sample_V2": kt / px.c_int, "dark_shot_V2": n_dark * (Q / c) ** 2,
             "readout_V2": design.noise.v_read ** 2}
    return {**parts, "dark_e": n_dark, "total_V": math.sqrt(sum(parts.values()))}


def figures(design, v_start: float | None = None) -> dict:
    """Knee, I_max, noise floor, CVDR, I_min and the DR of the closed form."""
    px, cd = design.pixel, design.coding
    v_start = px.v_reset if v_start is None else v_start
    t_exp = (2 ** cd.steps) * cd.t_unit
    dq = float(delta_q(design, v_start, px.v0))
    c = node_capacitance(design, v_start)
    nz = noise(design, v_start)
    v_n = nz["total_V"]
    cvdr = 20 * math.log10((v_start - px.v0) / v_n)
    i_min = c * v_n / t_exp
    return {"i_knee_A": dq / t_exp, "i_max_A": dq / cd.t_unit, "v_noise_V": v_n, "noise": nz, "cvdr_db": cvdr,
            "i_min_A": i_min, "dr_formula_db": cvdr + 20 * math.log10(2 ** cd.steps),
            "dr_model_db": 20 * math.log10(dq / cd.t_unit / i_min), "c_node_F": c}
