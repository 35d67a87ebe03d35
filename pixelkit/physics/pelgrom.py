"""Mismatch coefficients (Pelgrom): one device's threshold and current-factor sigma, a capacitor's.

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

The array's offsets estimated from them (with the follower's gain from SPICE): ``mc.pelgrom``.
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
