"""The pixel's source follower in any inversion level: the EKV model (gain, gm / I_D, thermal noise).

The follower (bulk at ground, drain at the supply, the column load sinking I) sits in
moderate inversion at the kit's biases (gm / I_D ~ 20 /V at 400 nA): neither the
weak-inversion (gm = I / (n U_T)) nor the strong-inversion (gm = sqrt(2 K I)) closed form
holds. EKV [Enz, Krummenacher, Vittoz 1995] covers both with one expression:

    V_P = V_G - V_T0 - gamma (sqrt(V_G - V_T0 + (sqrt(phi) + gamma/2)^2) - (sqrt(phi) + gamma/2))
    n   = 1 + gamma / (2 sqrt(V_P + phi))            (slope factor at V_P)
    I   = I_spec ln^2(1 + exp((V_P - V_S) / (2 U_T))),   I_spec = 2 n KP (W / L) U_T^2

in saturation. With the current fixed by the load, the source follows V_P:

    dV_S/dV_G = (dV_P/dV_G) (1 - (V_P - V_S)-term of n's change) ~ 1 / n,

computed here by differentiating the model numerically; the column load's output
conductance g_L (from its own inversion level and the card's channel-length modulation,
``lambda_L``) costs A = gms / (gms + g_L) on top, gms = n gm the source
transconductance. The inversion coefficient IC = I / I_spec sets

    gm / I = (1 / (n U_T)) 2 / (1 + sqrt(1 + 4 IC))       (EKV's interpolation)

and the channel's thermal noise, S_id = 4 k T gamma_n gm with
gamma_n = n (1/2 + 2 IC / 3) / (1 + IC) (1/2 n in weak, 2/3 n in strong inversion).

The parameters (VT0, gamma, phi, KP; the load's lambda) are the model library's, fitted
once per device size by ``techfit.ekv`` from ngspice operating points of the same devices.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..constants import K_B, Q


@dataclass(frozen=True)
class Ekv:
    vt0: float      # V
    gamma: float    # V^0.5
    phi: float      # V
    kp: float       # A / V^2 (mu Cox)

    def v_p(self, v_g: float) -> float:
        a = math.sqrt(self.phi) + self.gamma / 2
        x = max(v_g - self.vt0 + a * a, 1e-12)
        return v_g - self.vt0 - self.gamma * (math.sqrt(x) - a)

    def n(self, v_p: float) -> float:
        return 1.0 + self.gamma / (2.0 * math.sqrt(max(v_p + self.phi, 1e-6)))

    def i_spec(self, v_p: float, w_over_l: float, temperature_K: float) -> float:
        ut = K_B * temperature_K / Q
        return 2.0 * self.n(v_p) * self.kp * w_over_l * ut * ut

    def v_s(self, v_g: float, i: float, w_over_l: float, temperature_K: float) -> float:
        """The source voltage that carries ``i`` in saturation (the follower's output)."""
        ut = K_B * temperature_K / Q
        vp = self.v_p(v_g)
        r = math.sqrt(i / self.i_spec(vp, w_over_l, temperature_K))
        return vp - 2.0 * ut * math.log(math.expm1(r))


def ic(model: Ekv, v_g: float, i: float, w_over_l: float, temperature_K: float) -> float:
    """Inversion coefficient I / I_spec."""
    return i / model.i_spec(model.v_p(v_g), w_over_l, temperature_K)


def gm_over_id(model: Ekv, v_g: float, i: float, w_over_l: float, temperature_K: float) -> float:
    """gm / I_D (1/V) of the gate transconductance."""
    ut = K_B * temperature_K / Q
    n = model.n(model.v_p(v_g))
    return 2.0 / (n * ut * (1.0 + math.sqrt(1.0 + 4.0 * ic(model, v_g, i, w_over_l, temperature_K))))


def gain(model: Ekv, v_g: float, i: float, w_over_l: float, temperature_K: float, g_load: float = 0.0,
         dv: float = 1e-3) -> float:
    """dV_S / dV_G of the follower carrying ``i`` into a load of output conductance ``g_load``."""
    ideal = (model.v_s(v_g + dv, i, w_over_l, temperature_K)
             - model.v_s(v_g - dv, i, w_over_l, temperature_K)) / (2 * dv)
    if g_load <= 0:
        return ideal
    gms = gm_over_id(model, v_g, i, w_over_l, temperature_K) * i * model.n(model.v_p(v_g))
    return ideal * gms / (gms + g_load)


def noise_factor(model: Ekv, v_g: float, i: float, w_over_l: float, temperature_K: float) -> float:
    """gamma_n of S_id = 4 k T gamma_n gm (module docstring)."""
    x = ic(model, v_g, i, w_over_l, temperature_K)
    return model.n(model.v_p(v_g)) * (0.5 + 2.0 * x / 3.0) / (1.0 + x)


def follower_gain(design, models: dict, v_fd: float | None = None) -> float:
    """A_sf of the pixel's follower at FD = ``v_fd`` (default the PD reset level), EKV (within 3.3 % of ngspice's
    two-point gain of the full read chain from 0.1 to 4 uA and 1.3 to 2.4 V: ``tests/test_sf.py``)."""
    dev = design.pixel.devices
    v = design.pixel.v_pd_reset if v_fd is None else v_fd
    return gain(models["sf"], v, design.pixel.sf_bias, dev.sf_w / dev.sf_l, design.temperature)


def column(design, models: dict, v_fd: float | None = None) -> dict:
    """The read chain's small-signal figures at FD = ``v_fd``: each device's gm, noise factor and inversion
    coefficient, the row switch's resistance and the column's source impedance Z = 1 / gms + R_rs."""
    dev, px, temp = design.pixel.devices, design.pixel, design.temperature
    m = models
    v = px.v_pd_reset if v_fd is None else v_fd
    i = px.sf_bias
    wl_sf, wl_ld, wl_rs = dev.sf_w / dev.sf_l, dev.load_w / dev.load_l, dev.rs_w / dev.rs_l
    gm_sf = gm_over_id(m["sf"], v, i, wl_sf, temp) * i
    gms = m["sf"].n(m["sf"].v_p(v)) * gm_sf
    vg_ld = _gate_for(m["load"], i, wl_ld, temp)
    gm_ld = gm_over_id(m["load"], vg_ld, i, wl_ld, temp) * i
    r_rs = 1.0 / _linear_conductance(m["rs"], design.tech.supply, m["sf"].v_s(v, i, wl_sf, temp), wl_rs, temp)
    return {"gm_sf": gm_sf, "gms": gms, "gm_load": gm_ld, "r_rs_ohm": r_rs, "z_ohm": 1.0 / gms + r_rs,
            "gamma_sf": noise_factor(m["sf"], v, i, wl_sf, temp),
            "gamma_load": noise_factor(m["load"], vg_ld, i, wl_ld, temp),
            "gm_over_id_sf": gm_sf / i, "gm_over_id_load": gm_ld / i,
            "ic_sf": ic(m["sf"], v, i, wl_sf, temp), "ic_load": ic(m["load"], vg_ld, i, wl_ld, temp)}


def column_thermal(design, models: dict, c_col: float, v_fd: float | None = None) -> dict:
    """Thermal noise of one column sample (V^2) from the follower, its load, the load's bias mirror and the row
    switch, EKV at each device's own inversion level (``column``).

    The SF's and the load's channel currents (4 k T gamma_n gm each; the diode-connected bias device's noise
    is copied onto the load by the mirror: the load's term twice) flow through the column's source impedance
    Z, and the row switch adds its own 4 k T R_rs; the column capacitance low-passes the sum with
    tau = Z C_col, so one sample holds S_white / (4 Z C_col). In weak inversion with no switch this is
    1.5 kT / C_col (kT / C_col from the follower and the load, half of it again from the mirror)."""
    from ..constants import K_B
    c = column(design, models, v_fd)
    kt, z = K_B * design.temperature, c["z_ohm"]
    psd = {"sf": 4 * kt * c["gamma_sf"] * c["gm_sf"] * z * z,
           "load_and_mirror": 4 * kt * 2 * c["gamma_load"] * c["gm_load"] * z * z,
           "row_switch": 4 * kt * c["r_rs_ohm"]}
    per_sample = {k: v / (4 * z * c_col) for k, v in psd.items()}
    return {"variance_V2": sum(per_sample.values()), "parts_V2": per_sample, "white_psd_V2_per_Hz": sum(psd.values()),
            **c}


def _gate_for(model: Ekv, i: float, w_over_l: float, temperature_K: float) -> float:
    """The gate voltage of a grounded-source device carrying ``i`` in saturation."""
    from scipy.optimize import brentq
    return float(brentq(lambda vg: model.v_s(vg, i, w_over_l, temperature_K), 0.0, 3.0))


def _linear_conductance(model: Ekv, v_g: float, v_s: float, w_over_l: float, temperature_K: float) -> float:
    """Channel conductance at V_DS = 0 (a closed switch): dI/dV_D of EKV's forward - reverse current."""
    ut = K_B * temperature_K / Q
    vp = model.v_p(v_g)
    x = (vp - v_s) / (2 * ut)
    return model.i_spec(vp, w_over_l, temperature_K) / ut * math.log1p(math.exp(x)) / (1 + math.exp(-x))
