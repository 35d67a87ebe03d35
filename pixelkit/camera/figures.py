"""EMVA 1288 (release 3.0 / 4 Linear) figures from mean and variance curves.

    K        slope of (var - var_dark) against (mean - mean_dark) over 0 - 70 % of saturation
    R        slope of (mean - mean_dark) against mu_p over the same range; eta = R / K
             (both lines through the origin, as the emva1288 reference implementation fits)
    sigma_d  sqrt(var_dark - 1/12) / K  (e-, at the first exposure)
    sat      at the variance maximum: mu_p.sat there, mu_e.sat = eta mu_p.sat (EMVA 1288 3.0; for a
             response that compresses before it clips this is above (mean_sat - mean_dark) / K)
    SNR_max  sqrt(mu_e.sat);  DR = mu_p.sat / mu_p.min, mu_p.min = (sigma_d + 1/2) / eta
    LE       (max delta - min delta) / 2, delta = (mean - fit) / fit of a line through the
             origin of (mean - mean_dark) against mu_p over 5 - 95 % of saturation

Applied to the analytic curves of ``ptc.analytic`` they are what the model says an
EMVA measurement of this pixel finds (a C(V) pixel is not linear, so K over 0 - 70 %
differs from the zero-signal conversion gain); a reader of the exported images is
the independent path that must find them again.
"""
from __future__ import annotations

import numpy as np


def _through_origin(x, y) -> float:
    return float(np.sum(x * y) / np.sum(x * x))


def emva_figures(mu_p, mean, var, dark_mean, dark_var) -> dict:
    mu_p, y, v = (np.asarray(a, float) for a in (mu_p, mean, var))
    yd, vd = np.asarray(dark_mean, float), np.asarray(dark_var, float)
    i_sat = int(np.argmax(v))
    y_sat = y[i_sat] - yd[i_sat]
    sig = y - yd
    lin = np.arange(int(np.nonzero(sig <= 0.7 * y_sat)[0].max()) + 1)
    k = _through_origin(sig[lin], (v - vd)[lin])
    r = _through_origin(mu_p[lin], sig[lin])
    eta = r / k
    sigma_d = float(np.sqrt(max(vd[0] - 1.0 / 12.0, 0.0)) / k)
    sat_p = float(mu_p[i_sat])
    sat_e = eta * sat_p
    p_min = (sigma_d + 0.5) / eta
    le_rng = (sig >= 0.05 * y_sat) & (sig <= 0.95 * y_sat)
    slope = _through_origin(mu_p[le_rng], sig[le_rng])
    delta = (sig[le_rng] - slope * mu_p[le_rng]) / (slope * mu_p[le_rng])
    return {"k_dn_per_e": k, "qe": eta, "read_noise_e": sigma_d, "saturation_e": sat_e,
            "saturation_p": sat_p, "snr_max_db": 10.0 * np.log10(sat_e), "dr_db": 20.0 * np.log10(sat_p / p_min),
            "linearity_error_pct": float(100.0 * (delta.max() - delta.min()) / 2.0)}
