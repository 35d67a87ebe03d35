"""Mismatch coefficients and the analytic (Pelgrom) estimates of the array's offsets.

Sources, in this order:

- MOSFETs: the GF180MCU model library's own statistical model (``sm141064.ngspice``,
  section ``fets_mm``): each ``nfet_03v3`` / ``pfet_03v3`` instance draws
  ``delvto = agauss(0, 0.7071 par_vth 1e-6 / sqrt(Leff Weff))`` and
  ``mulu0 = 1 - agauss(0, 0.7071 par_k 1e-6 / sqrt(Leff Weff))`` with
  ``Leff = L - par_l``, ``Weff = W - par_w`` when ``sw_stat_mismatch = 1``. The
  coefficients are read from that file here, so the estimate and the simulation use
  the same numbers and nothing is copied by hand. (``par_vth`` is the pair coefficient
  A_VT in V um; 0.7071 = 1/sqrt(2) turns it into one device's sigma.)
- Capacitors: the technology file's ``[mismatch]`` table (sigma(dC/C) = A_C / sqrt(area),
  area = C / density); the kit draws them (``circuits.array.afe_caps``).

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

import math
import re
from functools import lru_cache

from ..errors import ConfigError
from ..readfile import read_bytes

_COEFS = ("par_vth", "par_k", "par_l", "par_w")


@lru_cache(maxsize=8)
def _coefficients(model_file: str, device: str) -> dict:
    text = read_bytes(model_file, "model file", "model").decode("utf-8", errors="replace")
    start = text.find(".lib fets_mm")
    head = text.find(f".subckt {device} ", start)
    if start < 0 or head < 0:
        raise ConfigError(model_file, "fets_mm", device, "a model library with the GF180MCU mismatch section")
    body = text[head:text.find(".ends", head)]
    out = {}
    for name in _COEFS:
        m = re.search(rf"\b{name}\s*=\s*([-+0-9.eE]+)", body)
        if not m:
            raise ConfigError(model_file, f"{device}.{name}", None, "a mismatch coefficient in the model card")
        out[name] = float(m.group(1))
    return out


def coefficients(design, kind: str = "n") -> dict:
    """The Pelgrom coefficients of the design's NMOS (``n``) or PMOS (``p``) model."""
    mos = design.tech.mos
    device = mos.nmos if kind == "n" else mos.pmos
    for inc in design.tech.models.includes(design.corner or None):
        if inc.kind == "lib":
            return _coefficients(str(inc.file), device)
    raise ConfigError(design.tech.source, "models", None, "a model library (lib FILE SECTION)")


def sigma_vth(design, w: float, l: float, kind: str = "n") -> float:
    """One device's threshold sigma (V), as the model library draws it."""
    c = coefficients(design, kind)
    return 0.7071 * c["par_vth"] * 1e-6 / math.sqrt((l - c["par_l"]) * (w - c["par_w"]))


def sigma_beta(design, w: float, l: float, kind: str = "n") -> float:
    """One device's relative current-factor (mobility) sigma, as the model library draws it."""
    c = coefficients(design, kind)
    return 0.7071 * c["par_k"] * 1e-6 / math.sqrt((l - c["par_l"]) * (w - c["par_w"]))


def cap_sigma_rel(design, c: float) -> float:
    """Relative sigma of a capacitor of ``c`` farads (technology ``[mismatch]``)."""
    mm = design.tech.mismatch
    if mm is None:
        raise ConfigError(design.tech.source, "mismatch", None,
                          "a [mismatch] table (cap_pelgrom, cap_density) for capacitor Monte Carlo")
    return mm.cap_pelgrom / math.sqrt(c / mm.cap_density)


def sf_gain(design, v_fd: float, dv: float = 0.05, backend: str = "batch") -> float:
    """dV_col/dV_FD of the pixel's source follower (RS on, column load) around ``v_fd``."""
    from ..circuits.testbench import sf_bench
    from ..spice import simulate_many
    lo, hi = simulate_many([sf_bench(design, v_fd - dv, title="sf_lo"), sf_bench(design, v_fd + dv, title="sf_hi")],
                           backend=backend)
    return float((hi["v(col)"][0] - lo["v(col)"][0]) / (2 * dv))


def reset_offset_sigma(design, backend: str = "batch") -> dict:
    """The Pelgrom estimate of sigma(column reset level) and its parts (V)."""
    dev = design.pixel.devices
    s_sf = sigma_vth(design, dev.sf_w, dev.sf_l)
    g = sf_gain(design, design.pixel.v_fd_reset, backend=backend)
    return {"sigma_vth_sf_V": s_sf, "sf_gain": g, "sigma_reset_V": g * s_sf,
            "sigma_vth_rst_V": sigma_vth(design, dev.rst_w, dev.rst_l),
            "sigma_beta_sf": sigma_beta(design, dev.sf_w, dev.sf_l)}
