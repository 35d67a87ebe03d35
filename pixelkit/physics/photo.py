"""Photocurrent from irradiance and spectrum ([Thesis2019] eq. 3.2, 3.3); radiometry <-> photometry.

    I_ph = integral eta(lambda) E(lambda) A_eff q lambda / (h c) dlambda
         = integral R(lambda) E(lambda) A_eff dlambda,   R = eta q lambda / (h c)
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..constants import C0, H, KM, Q

# CIE 1924 photopic luminous efficiency V(lambda), 380-780 nm in 10 nm steps.
_V_NM = np.arange(380, 790, 10, dtype=float)
_V = np.array([0.00004, 0.00012, 0.0004, 0.0012, 0.004, 0.0116, 0.023, 0.038, 0.06, 0.09098,
               0.13902, 0.20802, 0.323, 0.503, 0.71, 0.862, 0.954, 0.99495, 0.995, 0.952,
               0.87, 0.757, 0.631, 0.503, 0.381, 0.265, 0.175, 0.107, 0.061, 0.032, 0.017,
               0.00821, 0.004102, 0.002091, 0.001047, 0.00052, 0.000249, 0.00012, 0.00006,
               0.00003, 0.000015])


def photopic(wavelength_m):
    """CIE photopic V(lambda) (linear interpolation of the 10 nm table; 0 outside)."""
    return np.interp(np.asarray(wavelength_m) * 1e9, _V_NM, _V, left=0.0, right=0.0)


def responsivity(wavelength_m, qe):
    """Responsivity R = eta q lambda / (h c), in A/W."""
    return np.asarray(qe) * Q * np.asarray(wavelength_m) / (H * C0)


@dataclass(frozen=True)
class Spectrum:
    """Relative spectral power on a wavelength grid (m); a single line if one point."""
    wavelength_m: tuple
    relative_power: tuple

    @classmethod
    def monochromatic(cls, wavelength_m: float) -> "Spectrum":
        return cls((float(wavelength_m),), (1.0,))

    @classmethod
    def blackbody(cls, temperature_K: float, lo=350e-9, hi=1100e-9, n=376) -> "Spectrum":
        """Planck spectrum (CIE illuminant A is 2856 K: a halogen headlight)."""
        wl = np.linspace(lo, hi, n)
        k_b = 1.380649e-23
        p = 1.0 / (wl ** 5 * np.expm1(H * C0 / (wl * k_b * temperature_K)))
        return cls(tuple(wl), tuple(p / p.max()))

    @classmethod
    def white_led(cls, pump_nm: float = 450.0, pump_width_nm: float = 20.0, phosphor_nm: float = 565.0,
                  phosphor_width_nm: float = 110.0, phosphor_peak: float = 0.6, lo=350e-9, hi=1100e-9,
                  n=376) -> "Spectrum":
        """A phosphor-converted white LED (an LED headlight): the blue pump and the yellow phosphor band,
        each in the band shape of [Ohno2005] g = (exp(-x^2) + 2 exp(-5 x^2)) / 3, x = (lambda - peak) /
        width (the pump 20 nm, the phosphor 110 nm wide at 0.6 of the pump's peak: a cool white; its
        luminous efficacy over 350 - 1100 nm is 332 lm/W, a 2856 K black body's 54). What matters to a
        pixel: 1.7 % of its power lies beyond 700 nm, where a halogen lamp puts 78 %."""
        wl = np.linspace(lo, hi, n)

        def band(peak, width):
            x = (wl * 1e9 - peak) / width
            return (np.exp(-x * x) + 2 * np.exp(-5 * x * x)) / 3
        p = band(pump_nm, pump_width_nm) + phosphor_peak * band(phosphor_nm, phosphor_width_nm)
        return cls(tuple(wl), tuple(p / p.max()))

    def _weights(self):
        wl = np.asarray(self.wavelength_m)
        p = np.asarray(self.relative_power)
        if wl.size == 1:
            return wl, np.ones(1)
        w = np.gradient(wl) * p          # trapezoid-like weights on the grid
        return wl, w / w.sum()           # fraction of the total power per grid point

    def mean(self, f) -> float:
        """Power-weighted mean of ``f(wavelength)`` over the spectrum."""
        wl, w = self._weights()
        return float(np.sum(w * f(wl)))


def photocurrent(irradiance_W_m2: float, area_m2: float, spectrum: Spectrum, qe_of) -> float:
    """Photocurrent of ``area_m2`` under total irradiance ``irradiance_W_m2`` (A).

    ``qe_of`` maps wavelength (m) to quantum efficiency (e.g. ``technology.qe``).
    """
    r = spectrum.mean(lambda wl: responsivity(wl, qe_of(wl)))
    return r * irradiance_W_m2 * area_m2


def luminous_efficacy(spectrum: Spectrum) -> float:
    """lm per W of the spectrum: K_m * <V(lambda)>."""
    return KM * spectrum.mean(photopic)


def lux_to_irradiance(lux: float, spectrum: Spectrum) -> float:
    """Illuminance (lx) -> irradiance (W/m^2) for light of the given spectrum."""
    eff = luminous_efficacy(spectrum)
    if eff <= 0:
        raise ValueError("the spectrum has no visible power: illuminance is undefined")
    return lux / eff


def irradiance_to_lux(irradiance: float, spectrum: Spectrum) -> float:
    return irradiance * luminous_efficacy(spectrum)
