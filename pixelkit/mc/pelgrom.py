"""The analytic (Pelgrom) estimate of the array's offsets, from the coefficients of
``physics.pelgrom`` and the follower's gain measured in SPICE.

Analytic estimate checked against Monte Carlo (``tests/test_montecarlo.py``): the
pixel-to-pixel spread of the column's reset level (the offset FPN before double
sampling) is dominated by the source follower's threshold:

    sigma(V_reset,col) ~= G_SF sigma_VT(SF)

with G_SF = dV_col / dV_FD the follower's gain at the reset level (from two operating
points of the SF bench, a deterministic nominal simulation). Neglected: the RST
switch's threshold through its channel-charge split onto FD (at most
0.5 Cox W L sigma_VT(RST) / C_FD, i.e. adds < 10 % in quadrature here), the SF's and
load's current factor (Id/gm x sigma_beta: < 1 %) and the RS switch in triode.
"""
from __future__ import annotations

from ..camera.spicenoise import sf_gain
from ..physics.pelgrom import sigma_beta, sigma_vth


def reset_offset_sigma(design, backend: str = "batch") -> dict:
    """The Pelgrom estimate of sigma(column reset level) and its parts (V)."""
    dev = design.pixel.devices
    s_sf = sigma_vth(design, dev.sf_w, dev.sf_l)
    g = sf_gain(design, design.pixel.v_fd_reset, dv=0.05, backend=backend)
    return {"sigma_vth_sf_V": s_sf, "sf_gain": g, "sigma_reset_V": g * s_sf,
            "sigma_vth_rst_V": sigma_vth(design, dev.rst_w, dev.rst_l),
            "sigma_beta_sf": sigma_beta(design, dev.sf_w, dev.sf_l)}
