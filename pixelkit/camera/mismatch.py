"""Seeded per-pixel mismatch of the virtual camera, from the technology and the devices.

A simple model (the Monte Carlo of the scale issue replaces it):

- **Offset (DSNU).** The SF threshold cancels in the double sampling (the same SF
  reads both samples), but the TG's channel charge, which half lands on FD when TG
  opens, differs from pixel to pixel through the TG threshold: sigma_off =
  1/2 Cox W L sigma_VT / C_FD at FD, times A_sf, with sigma_VT the model library's
  own Pelgrom coefficient for the TG's W and L (``physics.pelgrom.sigma_vth``).
- **Gain (PRNU).** The photoactive area's edge is placed to within the layout grid
  (``rules.grid``): a masked opening of side a varies by 2 sigma_edge / a in
  relative area, an unmasked PD by the same over its own side; the PD junction's
  capacitance by A_C / sqrt(area), A_C the technology's capacitor matching
  (``[mismatch] cap_pelgrom``; ``A_C`` below when the technology has none).
- **Dark current** spreads by ``DARK_SPREAD`` (lognormal sigma) from pixel to pixel.

The two constants below are typical values for the 0.35 um class,
assumptions (not measured).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..physics.pelgrom import sigma_vth
from ..physics import fd

A_C = 0.01e-6        # relative C mismatch x sqrt(area): 1 % um [A]
DARK_SPREAD = 0.2    # lognormal sigma of the dark current      [A]


@dataclass(frozen=True)
class Mismatch:
    gain: np.ndarray       # relative photo-response per pixel (mean 1)
    offset_V: np.ndarray   # column offset per pixel
    dark: np.ndarray       # dark-current multiplier per pixel (mean 1)
    sigma_gain: float
    sigma_offset_V: float


def sigmas(design, which: str, a_sf: float) -> tuple[float, float]:
    """(relative gain sigma, offset sigma in V at the column) of ``which`` array."""
    sub, tech, dev = getattr(design, which), design.tech, design.pixel.devices
    side = float(np.sqrt(sub.photoactive_area))
    s_edge = 2.0 * tech.rules.grid / side
    a_c = tech.mismatch.cap_pelgrom if getattr(tech, "mismatch", None) is not None else A_C
    s_cap = a_c / np.sqrt(sub.area)
    c_fd = float(fd.fd_node(design, a_sf).capacitance(design.pixel.v_pd_reset))
    s_vt = sigma_vth(design, dev.tg_w, dev.tg_l)
    s_off = a_sf * 0.5 * tech.mos.cox * dev.tg_w * dev.tg_l * s_vt / c_fd
    return float(np.hypot(s_edge, s_cap)), float(s_off)


def draw(design, which: str, a_sf: float, shape, seed: int) -> Mismatch:
    sg, so = sigmas(design, which, a_sf)
    rng = np.random.default_rng([seed, 1 if which == "primary" else 2])
    return Mismatch(gain=1.0 + sg * rng.standard_normal(shape), offset_V=so * rng.standard_normal(shape),
                    dark=rng.lognormal(-0.5 * DARK_SPREAD ** 2, DARK_SPREAD, shape),
                    sigma_gain=sg, sigma_offset_V=so)
