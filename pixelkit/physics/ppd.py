"""The pinned photodiode (PPD) and its transfer gate in closed form: the kit's derivations that the
SPICE model (``circuits.ppd``) is checked against.

State: the stored electrons Q (C, > 0). The PPD's n-region is fully depleted when empty; its
potential maximum then sits at the pinning voltage V_pin [Fossum2014]. Electrons fill the well from
the bottom, and with the full-depletion approximation of [Capoccia2019] the electrons' quasi-Fermi
potential V_F follows a linear capacitance C_PPD [Goiffon2014]:

    Q(V_F) = C_PPD U_T ln(1 + exp((V_pin - V_F) / U_T))        (-> C_PPD (V_pin - V_F) when full)

(the logarithm is the Boltzmann tail of an almost empty well: V_F may rise above V_pin only by
removing an exponentially small charge, so nothing can empty the PPD beyond empty). Its inverse
gives the one term every current law needs:

    exp(-V_F / U_T) = exp(-V_pin / U_T) (exp(Q / Q_T) - 1),     Q_T = C_PPD U_T.

- **Dark current and full well**: the n-region to the p-substrate / pinning layer is a diode whose
  saturation current is the *bulk diffusion* dark current I_dif (n_i^2: activation E_g); the
  *generation* current I_gen (depleted regions at the TG edge and the isolation sidewalls: n_i,
  E_g / 2) adds electrons at any potential. The well overflows into the substrate when
  ``I_dif (exp(-V_F/U_T) - 1) = I_ph + I_gen``, so the full well is

      FWC(I_ph) = Q(V_F,eq),  V_F,eq = -U_T ln(1 + (I_ph + I_gen) / I_dif)

  which is ``C_PPD V_pin`` plus a term logarithmic in the light: the equilibrium full well of
  [Pelamatti2013] in the dark, the light dependence that [Pelamatti2015] measured.
- **Transfer**: electrons leave over the potential barrier phi_B at the PPD's edge of the transfer
  gate by thermionic emission [Capoccia2019] [Fossum2014]: the TG channel potential is the EKV
  pinch-off voltage of the technology's NMOS at the TG's gate voltage, V_P(V_TG), less the design's
  edge barrier ``barrier`` (a pocket or barrier from the pinning implant under the TG edge):
  phi_B = V_P(V_TG) - barrier. The current is a forward-minus-reverse form with the PPD as the
  source and FD as the drain:

      I_TG = I_spec [ln(1 + exp((phi_B - V_F) / U_T)) - ln(1 + exp((phi_B - V_FD) / U_T))]

  (I_spec: the EKV specific current of the TG's size). Over a barrier it is EKV's weak inversion,
  thermionic emission; with no barrier left it grows linearly with the overdrive, a drift-limited
  transfer of time constant C_PPD U_T / I_spec (a fraction of a ns), where EKV's strong-inversion
  square law would be a MOSFET's channel, which the PPD is not.
  In its barrier-limited regime (phi_B well below V_F: the last electrons) this is
  ``I_spec exp((phi_B - V_F) / U_T) = a (exp(Q / Q_T) - 1)`` with ``a = I_spec exp((phi_B - V_pin) / U_T)``,
  and dQ/dt = -a (exp(Q/Q_T) - 1) integrates exactly (``residual``):

      Q(t) = -Q_T ln(1 - (1 - exp(-Q0 / Q_T)) exp(-t / tau)),    tau = Q_T / a

  - a logarithmic fall while Q >> Q_T, then an exponential tail with the thermionic emission time
    constant tau. The charge left after the TG pulse is the transfer-limited image lag.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..constants import K_B, Q
from .dark import bandgap


def thermal_voltage(temperature_K: float) -> float:
    return K_B * temperature_K / Q


@dataclass(frozen=True)
class Channel:
    """The TG channel: EKV parameters of the technology's NMOS at the TG's size (``physics.sf.Ekv``
    fields) and W / L."""
    vt0: float
    gamma: float
    phi: float
    kp: float
    w_over_l: float

    def v_p(self, v_g: float) -> float:
        a = math.sqrt(self.phi) + self.gamma / 2
        x = max(v_g - self.vt0 + a * a, 0.0)
        return v_g - self.vt0 - self.gamma * (math.sqrt(x) - a)

    def i_spec_on(self, temperature_K: float) -> float:
        """I_spec with the slope factor of the channel turned on (V_G = V_T0 + 2 V)."""
        return self.i_spec(temperature_K, self.vt0 + 2.0)

    def i_spec(self, temperature_K: float, v_g: float) -> float:
        ut = thermal_voltage(temperature_K)
        n = 1.0 + self.gamma / (2.0 * math.sqrt(max(self.v_p(v_g) + self.phi, 1e-6)))
        return 2.0 * n * self.kp * self.w_over_l * ut * ut


@dataclass(frozen=True)
class Ppd:
    """One PPD at one temperature (every current already at that temperature)."""
    v_pin: float          # V
    c: float              # F
    i_dif: float          # A, bulk diffusion dark current (the overflow diode's saturation current)
    i_gen: float          # A, generation dark current (TG edge, isolation)
    barrier: float        # V, below the TG channel's pinch-off potential
    channel: Channel
    temperature: float    # K

    @property
    def ut(self) -> float:
        return thermal_voltage(self.temperature)

    @property
    def q_t(self) -> float:
        return self.c * self.ut

    def charge(self, v_f: float) -> float:
        """Stored electrons (C) at quasi-Fermi potential ``v_f``."""
        x = (self.v_pin - v_f) / self.ut
        return self.q_t * (x + math.log1p(math.exp(-x)) if x > 0 else math.log1p(math.exp(x)))

    def potential(self, q: float) -> float:
        """Quasi-Fermi potential V_F (V) of ``q`` stored electrons (C)."""
        x = max(q / self.q_t, 1e-300)
        return self.v_pin - self.ut * (x + math.log(-math.expm1(-x)))

    def phi_b(self, v_tg: float) -> float:
        return self.channel.v_p(v_tg) - self.barrier

    def full_well(self, i_ph: float = 0.0) -> float:
        """Equilibrium full well (C) under photocurrent ``i_ph`` (A; 0: in the dark)."""
        v_eq = -self.ut * math.log1p((i_ph + self.i_gen) / self.i_dif)
        return self.charge(v_eq)

    def emission_rate(self, v_tg: float) -> float:
        """a (A): the barrier-limited transfer current is a (exp(Q / Q_T) - 1)."""
        return self.channel.i_spec_on(self.temperature) * math.exp((self.phi_b(v_tg) - self.v_pin) / self.ut)

    def tau(self, v_tg: float) -> float:
        """Thermionic emission time constant (s) of the last electrons."""
        return self.q_t / self.emission_rate(v_tg)

    def residual(self, q0: float, t: float, v_tg: float) -> float:
        """Electrons (C) left after a transfer of ``t`` from ``q0``, barrier-limited (module docstring)."""
        y0 = -math.expm1(-q0 / self.q_t)           # 1 - exp(-Q0 / Q_T)
        return -self.q_t * math.log1p(-y0 * math.exp(-t / self.tau(v_tg)))

    def transfer_current(self, q: float, v_tg: float, v_fd: float) -> float:
        """The transfer current (A), PPD -> FD positive (what the SPICE model evaluates)."""
        ut, phi = self.ut, self.phi_b(v_tg)
        i_s = self.channel.i_spec_on(self.temperature)
        fwd = math.log1p(math.exp((phi - self.v_pin) / ut) * math.expm1(q / self.q_t))
        rev = math.log1p(math.exp((phi - v_fd) / ut))
        return i_s * (fwd - rev)


def dark_scale(temperature_K: float, t_ref: float, kind: str) -> float:
    """I(T) / I(T_ref) of a dark-current component: ``diffusion`` ~ n_i^2 ~ T^3 exp(-E_g / kT),
    ``generation`` ~ n_i ~ T^1.5 exp(-E_g / 2kT) (E_g(T) of silicon, ``dark.bandgap``)."""
    kq = K_B / Q

    def ni2(t):
        return t ** 3 * math.exp(-bandgap(t) / (kq * t))
    r = ni2(temperature_K) / ni2(t_ref)
    if kind == "diffusion":
        return r
    if kind == "generation":
        return math.sqrt(r)
    raise ValueError(kind)


def pinning_voltage(v_pin: float, v_bi: float | None, temperature_K: float, t_ref: float) -> float:
    """V_pin (V) at ``temperature_K`` of a PPD whose pinning voltage is ``v_pin`` at ``t_ref``: the one value
    without ``v_bi``; else it follows the junctions' built-in potential (``v_bi`` at ``t_ref``), which falls as
    n_i rises: V_bi(T) = U_T ln(N_A N_D / n_i(T)^2), so V_bi(T) = U_T(T) (v_bi / U_T(t_ref) - ln(n_i^2(T) /
    n_i^2(t_ref))) (``dark_scale``'s n_i^2), and V_pin(T) = v_pin - (V_bi(T) - v_bi): the depleted well's
    potential maximum is the pinning layer's potential plus what the junction's built-in potential no longer
    holds back [Pelamatti2015]."""
    if v_bi is None:
        return v_pin
    vbi = thermal_voltage(temperature_K) * (v_bi / thermal_voltage(t_ref)
                                            - math.log(dark_scale(temperature_K, t_ref, "diffusion")))
    return v_pin - (vbi - v_bi)


def doubling_K(temperature_K: float, t_ref: float, kind: str) -> float:
    """The temperature step (K) that doubles a component near ``temperature_K``."""
    r = dark_scale(temperature_K + 0.5, t_ref, kind) / dark_scale(temperature_K - 0.5, t_ref, kind)
    return math.log(2.0) / math.log(r)


def electrons(charge_C: float) -> float:
    return charge_C / Q
