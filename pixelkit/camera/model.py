"""The designed pixel array as a camera: the analytic inputs of the virtual camera.

One ``ArrayCamera`` per array (primary, secondary), from the design:

- response: the pixel's transfer measured in SPICE (``camera.transfer``: the experiment's
  bench, the double-sampled column signal above the pedestal against the collected charge
  I t_window, a monotone cubic through its points, flat at the measured column swing
  beyond them). It carries FD charge sharing, C(V), the source follower's and
  the column's compression towards the bottom of the swing, which the analytic node
  (``node``: PD + FD with A_sf, kept for the zero-signal gain CG_out(0)) does not: over
  0 - 70 % of saturation the analytic response gave a K 10 % above the SPICE transfer's;
- dark current: the PD's (the kit's law) plus its EC/TG diffusions' (the models' law);
- temporal noise: the read-noise chain of ``physics.noise`` (pixel probe: NCDS at
  the column, without the dark shot noise, which the camera draws itself), signal
  and dark shot noise (Poisson), quantization;
- storage: row r waits t_pre + r t_row + s1_off on FD, picking up the FD leakage and
  1/gse of the PD's photocurrent (``fd``);
- QE (EMVA eta): the technology's QE at ``wavelength`` times the photoactive
  area over the pixel area (pitch^2): the secondary's mask opening is its fill factor;
- an ideal ADC: ``bits`` over 1.2 x the clip level, dark level at 128 DN.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.interpolate import PchipInterpolator

from ..constants import Q
from ..physics import fd
from ..physics.dark import dark_current
from ..physics.junction import Node
from ..physics.noise import chain
from ..physics.subpixel import pd_node
from ..techfit.ekv import models_for

ARRAYS = ("primary", "secondary")


@dataclass(frozen=True)
class Adc:
    bits: int
    full_scale_V: float
    offset_dn: float = 128.0

    @property
    def lsb_V(self) -> float:
        return self.full_scale_V / 2 ** self.bits

    def digitize(self, v):
        dn = np.rint(self.offset_dn + np.asarray(v) / self.lsb_V)
        return np.clip(dn, 0, 2 ** self.bits - 1).astype(np.int64)


@dataclass(frozen=True)
class ArrayCamera:
    name: str
    rows: int
    cols: int
    pitch_m: float
    eta: float                 # EMVA QE: electrons per photon on the pixel area
    wavelength_m: float
    node: Node                 # PD node + FD (shared after the transfer)
    v0: float                  # their bias at the start (the PD reset level)
    a_sf: float
    clip_V: float              # column swing
    transfer_e: tuple          # SPICE transfer: collected electrons ...
    transfer_V: tuple          # ... and the column signal above the pedestal (V), increasing
    read_V: float              # temporal read noise at the column (no dark shot)
    dark_e_per_s: float        # PD dark current
    fd_leak_V_per_s: float     # FD leakage, at the column
    pls_V_per_e: float         # column V per PD photo-electron per second of FD wait (1/gse)
    t_row: float
    t_pre: float               # end of transfer to the first row (t_pre + t_store of the design)
    t_s1: float                # signal sample within a row (the design's s1_off)
    t_int: float
    temperature_K: float
    adc: Adc
    chain: dict
    cg0: float                 # output-referred conversion gain at zero signal (physics.fd.response)

    @property
    def cg0_V_per_e(self) -> float:
        """Output-referred conversion gain at zero signal: CG_out(0) of ``physics.fd.response`` (the
        transfer, TG's turn-off and RS's turn-on), the same figure the design summary shows."""
        return self.cg0

    @property
    def k0_dn_per_e(self) -> float:
        return self.cg0_V_per_e / self.adc.lsb_V

    @cached_property
    def _transfer(self):
        v = np.minimum(np.maximum.accumulate(np.asarray(self.transfer_V, float)), self.clip_V)
        return PchipInterpolator(np.asarray(self.transfer_e, float), v, extrapolate=False)

    def signal_V(self, n_e):
        """Column signal (V) for ``n_e`` photo/dark electrons on the node (unclipped by noise)."""
        n_e = np.asarray(n_e, dtype=float)
        v = self._transfer(np.clip(n_e, 0.0, self.transfer_e[-1]))
        return np.where(n_e >= self.transfer_e[-1], self.clip_V, v)

    def slope_V_per_e(self, n_e):
        """d signal / d n at ``n_e`` (V per electron), 0 beyond the measured transfer."""
        n_e = np.asarray(n_e, dtype=float)
        d = self._transfer.derivative()(np.clip(n_e, 0.0, self.transfer_e[-1]))
        return np.where(n_e >= self.transfer_e[-1], 0.0, d)

    def t_wait(self, rows=None):
        """Storage wait (s) of each row's signal sample."""
        r = np.arange(self.rows if rows is None else rows)
        return self.t_pre + r * self.t_row + self.t_s1

    def electrons_for_fraction(self, frac: float) -> float:
        """Electrons that take the column to ``frac`` of its clip level."""
        n = np.linspace(0.0, self.transfer_e[-1], 20001)
        return float(np.interp(frac * self.clip_V, np.maximum.accumulate(self.signal_V(n)), n))


def combined_node(design, which: str, a_sf: float) -> Node:
    p = pd_node(design, which, parasitics=True)
    f = fd.fd_node(design, a_sf, which=which)
    return Node(p.terms + f.terms, p.c_fixed + f.c_fixed)


def array_camera(design, which: str, a_sf: float, transfer: dict, wavelength_m: float = 550e-9,
                 bits: int = 12, shape: tuple | None = None) -> ArrayCamera:
    """The camera of ``which`` array on its SPICE ``transfer`` (``camera.transfer``: response, swing).

    ``shape`` (rows, cols): the image size, default the design's array; a larger
    virtual sensor (same row time) gives the photon transfer more pixels per step.
    """
    sub, tech = getattr(design, which), design.tech
    clip = transfer[which]["swing_V"]
    t_e, t_v = transfer[which]["electrons"], transfer[which]["signal_V"]
    r = fd.response(design, which, a_sf, models_for(design))
    ch = chain(design, which, a_sf, models_for(design))
    read_var = sum(v for k, v in ch["variance_V2"].items() if k not in ("dark_shot", "fd_leakage_shot"))
    eta = float(tech.qe(wavelength_m)) * sub.photoactive_area / sub.pitch ** 2
    return ArrayCamera(
        name=which, rows=shape[0] if shape else sub.rows, cols=shape[1] if shape else sub.cols, pitch_m=sub.pitch, eta=eta, wavelength_m=wavelength_m,
        node=combined_node(design, which, a_sf), v0=design.pixel.v_pd_reset, a_sf=a_sf, clip_V=clip,
        transfer_e=t_e, transfer_V=t_v,
        read_V=float(np.sqrt(read_var)),
        dark_e_per_s=(dark_current(sub.area, sub.perimeter, design.temperature, tech.photodiode)
                      + fd.pd_switch_leakage(design)) / Q,
        fd_leak_V_per_s=a_sf * fd.leakage(design) / r["c_fd_F"],
        pls_V_per_e=a_sf * Q / (fd.gse(design, which) * r["c_fd_F"]),
        t_row=1.0 / sub.f_read, t_pre=sub.timing.t_pre + sub.timing.t_store,
        t_s1=sub.timing.row(1.0 / sub.f_read)["s1_off"], t_int=sub.t_int, temperature_K=design.temperature,
        adc=Adc(bits, 1.2 * clip), chain=ch, cg0=r["cg_out_V_per_e"])
