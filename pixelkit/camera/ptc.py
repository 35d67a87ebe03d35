"""Photon transfer of the virtual camera: the exposure series, its analytic curves, its images.

The series: a constant monochromatic irradiance that puts the array at half its
clip level at the design's integration time, and ``steps`` exposure times from
1/steps to 1.15 x the time to the clip level (EMVA 1288: >= 50 steps, dark pairs at
every exposure). ``analytic`` propagates the model exactly where it can: the mean
is the C(V) response of the mean charge, the temporal variance is
f'(n)^2 n (Poisson charge through the local gain) + the read noise, clipped as a
Gaussian at the column swing, + 1/12 DN^2 of quantization. ``frames`` draws images:
Poisson electrons per pixel and frame, the response, Gaussian read noise, the
per-pixel mismatch, the storage of each row, the ADC.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import norm

from ..constants import C0, H
from .mismatch import Mismatch


@dataclass(frozen=True)
class Series:
    t_exp_s: np.ndarray
    mu_p: np.ndarray           # mean photons per pixel area per exposure
    irradiance_W_m2: float
    photon_rate: float         # photons per pixel per second


def series(cam, steps: int = 50) -> Series:
    n_half = cam.electrons_for_fraction(0.5)
    rate = n_half / (cam.eta * cam.t_int)                       # photons / pixel / s
    t_full = cam.electrons_for_fraction(1.0) / (cam.eta * rate)
    t = np.linspace(1.15 * t_full / steps, 1.15 * t_full, steps)
    e = rate * H * C0 / cam.wavelength_m / cam.pitch_m ** 2
    return Series(t, rate * t, float(e), float(rate))


def _clipped(mu, sd, hi):
    """Mean and variance of N(mu, sd^2) clipped above at ``hi``."""
    sd = np.maximum(sd, 1e-30)
    a = (hi - mu) / sd
    phi, cdf = norm.pdf(a), norm.cdf(a)
    m = mu * cdf - sd * phi + hi * (1 - cdf)
    m2 = (mu ** 2 + sd ** 2) * cdf - sd * (mu + hi) * phi + hi ** 2 * (1 - cdf)
    return m, np.maximum(m2 - m ** 2, 0.0)


def analytic(cam, s: Series) -> dict:
    """EMVA quantities in DN for every step: mean and temporal variance, bright and dark."""
    lsb = cam.adc.lsb_V
    wait = float(np.mean(cam.t_wait()))
    out = {}
    for kind, photons in (("bright", s.mu_p), ("dark", np.zeros_like(s.mu_p))):
        n = cam.eta * photons + cam.dark_e_per_s * s.t_exp_s
        f = cam.signal_V(n)
        var = cam.slope_V_per_e(n) ** 2 * n + cam.read_V ** 2
        m, v = _clipped(f, np.sqrt(var), cam.clip_V)
        store = (cam.fd_leak_V_per_s + cam.pls_V_per_e * cam.eta * photons / s.t_exp_s) * wait
        out[kind] = (cam.adc.offset_dn + (m + store) / lsb, v / lsb ** 2 + 1.0 / 12.0)
    return {"mu_p": s.mu_p, "t_exp_s": s.t_exp_s, "mean_dn": out["bright"][0], "var_dn": out["bright"][1],
            "dark_mean_dn": out["dark"][0], "dark_var_dn": out["dark"][1]}


def frame(cam, mm: Mismatch, photons: float, t_exp: float, rng) -> np.ndarray:
    """One image (DN) after an exposure of ``t_exp`` to ``photons`` per pixel."""
    shape = (cam.rows, cam.cols)
    mean_e = cam.eta * photons * mm.gain + cam.dark_e_per_s * t_exp * mm.dark
    n = rng.poisson(mean_e).astype(float)
    v = cam.signal_V(n) + mm.offset_V + rng.normal(0.0, cam.read_V, shape)
    v = np.minimum(v, cam.clip_V)
    wait = cam.t_wait()[:, None]
    v = v + (cam.fd_leak_V_per_s + cam.pls_V_per_e * cam.eta * photons * mm.gain / t_exp) * wait
    return cam.adc.digitize(v)
