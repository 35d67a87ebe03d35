"""Temporal noise: kTC, shot noise, and the read-noise chain of the 5T pixel with NCDS.

The chain ([Thesis2019] fig. 3.3 sequence; all variances at the column, V^2):

- **Resets and transfer.** EC resets the PD node (kT C_PD in charge) and RST resets
  FD (kT C_FD) before the transfer: the common mode of the two carries charge
  variance kT (C_PD + C_FD), i.e. kT / C_total in voltage. While TG conducts, its
  channel noise drives the difference of the two nodes to equilibrium, kT / C_series;
  when TG opens, FD keeps C_PD / C_total of that difference. Together

      var(V_FD, signal sample) = kT / C_total + kT C_PD / (C_FD C_total) = kT / C_FD.

- **NCDS.** The reset level comes from a *new* RST reset (non-correlated double
  sampling): another kT / C_FD, uncorrelated. So 2 kT / C_FD at
  FD, times A_sf^2 at the column.
- **SF + column load (thermal)** (``sf.column_thermal``): the follower, its load
  and the load's bias mirror, each with its channel noise at its own inversion level
  (EKV: the follower sits in moderate inversion, gm / I_D ~ 20 /V, IC ~ 0.8 at
  400 nA), through the column's source impedance 1 / gms + R_rs (the row switch adds
  its own 4 k T R_rs): one sample holds S / (4 Z C_col), about 1.7 kT / C_col here
  (the weak-inversion closed form gave kT / C_col: it left out the mirror and the
  switch). Two uncorrelated samples.
- **SF + column load (1/f)** (``sf_flicker``). Each NMOS has gate-referred
  S_vg = kf_vg / (cox W L f^ef) (technology ``mos.kf_vg``, ``mos.ef``, fitted to the
  model library). The SF's reaches the column times A_sf; the load's drain-current
  noise gm_ld^2 S_vg,ld (twice: the bias device's, copied by the mirror) flows through
  the column's source impedance Z (EKV gm at each device's inversion level), so
  S_col = kf_vg / (cox f^ef) (A_sf^2 / (W L)_sf + 2 (gm_ld Z)^2 / (W L)_ld),
  low-passed by the column pole f_col = 1 / (2 pi Z C_col). The two NCDS samples
  are dt apart (signal, then the new reset's level), so the difference sees
  |1 - exp(-j 2 pi f dt)|^2 = 2 - 2 cos(2 pi f dt): 1/f below 1/dt cancels, above it
  the samples add. var = int S_col(f) (2 - 2 cos 2 pi f dt) / (1 + (f/f_col)^2) df.
- **Shot noise** of the dark charge (PD over t_int, FD over the storage wait) and
  of the signal (Poisson, sqrt(N)).
- **AFE** (probe ``afe``): kT/C of C12 (through the noise gain 1/beta) and C13, the
  op-amp's thermal noise folded by autozero + amplification and its 1/f noise
  high-passed by the autozero (CDS) filter: ``physics.afe_noise`` (derivation there),
  referred to the AFE input (the column).

Input-referred electrons divide by the output-referred conversion gain
(``fd.response``).
"""
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


def column_flicker_psd(design, a_sf: float, f, sf_models: dict):
    """1/f PSD (V^2/Hz) at the column from the SF, its load and the load's bias mirror, below the column pole:
    the SF's gate noise times A_sf^2, the load's (and, copied by the mirror, the bias device's) drain-current
    noise gm_ld^2 S_vg through the column's source impedance Z (``sf.column``; in weak inversion with no row
    switch gm_ld Z = A_sf)."""
    from .sf import column
    mos, dev = design.tech.mos, design.pixel.devices
    c = column(design, sf_models)
    ld = 2.0 * (c["gm_load"] * c["z_ohm"]) ** 2
    s1 = mos.kf_vg / mos.cox * (a_sf ** 2 / (dev.sf_w * dev.sf_l) + ld / (dev.load_w * dev.load_l))
    return s1 / np.asarray(f, dtype=float) ** mos.ef


def sf_flicker(design, a_sf: float, dt: float, c_col: float, sf_models: dict, points_per_decade: int = 100) -> float:
    """Variance (V^2) of the NCDS difference from the SF's and the load's 1/f noise (derivation above)."""
    if design.tech.mos.kf_vg <= 0:
        return 0.0
    from .sf import column
    f_col = 1.0 / (2 * np.pi * column(design, sf_models)["z_ohm"] * c_col)
    lo, hi = 1e-4 / dt, 1e4 * f_col
    f = np.logspace(np.log10(lo), np.log10(hi), int(points_per_decade * np.log10(hi / lo)) + 1)
    w = (2.0 - 2.0 * np.cos(2 * np.pi * f * dt)) / (1.0 + (f / f_col) ** 2)
    return float(np.trapezoid(column_flicker_psd(design, a_sf, f, sf_models) * w, f))


def ncds_interval(design, which: str) -> float:
    """Time from the signal sample to the (new reset's) reset-level sample of the first row."""
    from .timing import timings
    tm = timings(design, design.experiment.t_window)[which]
    return tm.t_reset_level(0) - tm.t_signal(0)


def column_capacitance(design, which: str = "primary") -> float:
    """Column line: its parasitic C plus the RS source and load drain junctions at zero bias
    (post-layout: the extracted line of ``which`` array, every row's share and the column circuit's)."""
    from .nodes import line_cap
    from .geometry import diffusion
    mos, dev = design.tech.mos, design.pixel.devices
    col = "col_p" if which == "primary" else "col_s0"
    c = line_cap(design, col)
    if design.post_layout is not None:
        c += design.post_layout.per_row[col]
    for w in (dev.rs_w, dev.load_w):
        a, p = diffusion(w, mos.diff_ext)
        c += mos.cj * a + mos.cjsw * (p - w) + mos.cjswg * w
    return c


def chain(design, which: str, a_sf: float, sf_models: dict, t_int: float | None = None, t_wait: float = 0.0) -> dict:
    """Read-noise budget of ``which`` subpixel: variances by source, totals in V and e-.

    ``t_int`` (default: the subpixel's ``t_int``) sets the dark shot noise; ``t_wait``
    the FD leakage shot noise of the storage.
    """
    from . import afe_noise, fd
    from .dark import dark_current
    from .sf import column_thermal
    sub, temp = getattr(design, which), design.temperature
    t_int = sub.t_int if t_int is None else t_int
    r = fd.response(design, which, a_sf, sf_models)
    kt = K_B * temp
    cg = r["cg_out_V_per_e"]
    c_col = column_capacitance(design, which)
    n_dark = dark_current(sub.area, sub.perimeter, temp, design.tech.photodiode) * t_int / Q
    n_fd = fd.leakage(design) * t_wait / Q
    col = {   # V^2 at the column (NCDS difference)
        "reset_common_mode": a_sf ** 2 * kt / r["c_total_F"],
        "tg_partition": a_sf ** 2 * kt * r["c_pd_node_F"] / (r["c_fd_F"] * r["c_total_F"]),
        "fd_reset_ncds": a_sf ** 2 * kt / r["c_fd_F"],
        "sf_load_thermal": 2.0 * column_thermal(design, sf_models, c_col)["variance_V2"],
        "sf_load_flicker": sf_flicker(design, a_sf, ncds_interval(design, which), c_col, sf_models),
        "dark_shot": n_dark * cg ** 2,
        "fd_leakage_shot": (n_fd * (r["c_total_F"] / r["c_fd_F"]) ** 2) * cg ** 2,
    }
    pixel = sum(col.values())
    afe_parts = afe_noise.input_variances(design)
    afe = sum(afe_parts.values())
    return {
        "which": which, "cg_out_V_per_e": cg, "a_sf": a_sf, "c_col_F": c_col,
        "variance_V2": col, "afe_input_V2": afe, "afe_variance_V2": afe_parts,
        "electrons": {k: float(np.sqrt(v) / cg) for k, v in {**col, **afe_parts}.items()},
        "pixel_V": float(np.sqrt(pixel)), "pixel_e": float(np.sqrt(pixel) / cg),
        "afe_V": float(np.sqrt(pixel + afe)), "afe_e": float(np.sqrt(pixel + afe) / cg),
        "dark_e": float(n_dark),
    }
