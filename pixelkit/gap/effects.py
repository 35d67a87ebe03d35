"""Candidate effects: compact physical augmentations of the nominal model (EFFECTS.md).

Each effect maps its parameters to terms of ``nominal.predict``: extra charge
``dq`` (C), a pixel-level signal shift ``dv_pix`` (V, + = more signal), an extra
AFE gain error ``deps`` or an AFE output shift ``dv_afe`` (V). Parameters have
physical bounds; ``scale`` is their typical size (the fit works in units of it).
Temperatures in the data are in degC; 25 degC is the reference of T-laws.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Param:
    name: str
    lo: float
    hi: float
    scale: float
    x0: float


def _t_law(X, td):
    return 2.0 ** ((X["T"] - 25.0) / td)


def _gse(X, p):            # storage node sees light while it waits: Q = i t_wait / GSE
    return {"dq": p[0] * X["i"] * X["t_wait"]}


def _fd_leakage(X, p):     # FD droops in the dark while it waits; T-doubling
    return {"dq": p[0] * _t_law(X, p[1]) * X["t_wait"]}


def _dark_current(X, p):   # PD dark current over the integration; T-doubling; perimeter-scaled
    per = np.where(X["arr"] == 0, 1.0, X["perimeter_ratio"])
    return {"dq": p[0] * per * _t_law(X, p[1]) * X["t_int"]}


def _charge_injection(X, p):  # reset-switch injection/feedthrough on the reset sample: AFE sees it
    return {"dv_afe": p[0] + p[1] * X["signal"]}


def _sf_gain(X, p):        # SF body effect: gain falls with the signal swing (compression)
    return {"dv_pix": -p[0] * X["signal"] ** 2}


def _afe_gain(X, p):       # op-amp gain lower than designed: extra eps
    return {"deps": p[0]}


def _coupling(X, p):       # light on an unshielded AFE: offset that follows the light, not the charge
    return {"dv_afe": -p[0] * X["i"] * X["afe"]}


def _crosstalk(X, p):      # light under the mask of the secondary: fraction of the unmasked PD's light
    return {"dq": p[0] * X["i"] * X["c_m"] * X["t_int"] * (X["arr"] == 1)}


def column_shift(X, gain_afe, offset, gain):
    """Column circuitry: per-row ``offset`` (V) and relative ``gain`` error of the sampled signal.

    The pixel probe falls by gain x signal; the AFE output (inverting, gain_afe) rises by it.
    """
    return offset - gain * X["signal"] * np.where(X["afe"], -gain_afe, 1.0)


def _lag(X, p):            # image lag: a fraction of the previous frame's charge stays
    return {"dq": p[0] * X["i_prev"] * X["t_int"]}


EFFECTS = {
    "gse": ((Param("pls", 0.0, 0.1, 1e-3, 1e-4),), _gse),
    "fd_leakage": ((Param("i_fd_A", 0.0, 1e-11, 1e-14, 1e-15), Param("t_double_K", 3.0, 15.0, 1.0, 7.0)),
                   _fd_leakage),
    "dark_current": ((Param("i_d_A", 0.0, 1e-11, 1e-14, 1e-15), Param("t_double_K", 3.0, 15.0, 1.0, 7.0)),
                     _dark_current),
    "charge_injection": ((Param("offset_V", -0.2, 0.2, 1e-2, 0.0), Param("slope", -0.2, 0.2, 1e-2, 0.0)),
                         _charge_injection),
    "sf_gain": ((Param("k_per_V", -1.0, 1.0, 1e-2, 0.0),), _sf_gain),
    "afe_gain": ((Param("eps_extra", -0.05, 1.0, 1e-2, 0.0),), _afe_gain),
    "coupling": ((Param("k_V_per_A", 0.0, 1e9, 1e6, 1e4),), _coupling),
    "crosstalk": ((Param("k_xt", 0.0, 0.2, 1e-3, 1e-4),), _crosstalk),
    "column_fpn": ((), None),   # per-column offset and gain: built from the data (fit.py)
    "lag": ((Param("lag", 0.0, 0.5, 1e-2, 1e-3),), _lag),
}

NAMES = tuple(EFFECTS)
