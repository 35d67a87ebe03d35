"""Camera-level gap analysis of an EMVA 1288 descriptor dataset.

Nominal model (EMVA 1288 Linear): mu_y = mu_y.dark + R mu_p with R = K eta,
sigma_y^2 = sigma_y.dark^2 + K (mu_y - mu_y.dark), clipped at the ADC's full
scale; K from the photon-transfer slope and R from the response slope over
0 - 70 % of saturation, dark level and noise from the dark pairs, the dark
current from the slope of the dark level against exposure.

Where: residuals of the mean and of the variance against the nominal model,
by fraction of saturation. Which: candidate camera-level augmentations, each
fitted on the even exposure steps and judged on the odd (held-out) ones:

- ``nonlinearity``: response compression mu = mu_d + R mu_p (1 - b R mu_p)
  (the pixel-level ``sf_gain`` / C(V) signature);
- ``soft_saturation``: pixels do not all clip at once: each pixel's value is
  clipped at full scale and the mean is taken over a Gaussian spread of
  pixel responses (PRNU s times the signal, plus temporal noise);
- ``dark_current``: the dark level grows with exposure (mu += D t).
"""
from __future__ import annotations

from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
from scipy.optimize import least_squares
from scipy.stats import norm

from ..errors import ConfigError


def read_descriptor(folder: str | Path) -> dict:
    folder = Path(folder)
    path = folder / "EMVA1288_Data.txt" if folder.is_dir() else folder
    if not path.is_file():
        raise ConfigError(str(path), "emva dataset", str(folder), "a folder with EMVA1288_Data.txt")
    base = path.parent
    steps, cur, bits = [], None, 8
    for k, line in enumerate(path.read_text().splitlines(), 1):
        f = line.split()
        if not f or f[0].startswith("#"):
            continue
        if f[0] == "n":
            bits = int(f[1])
        elif f[0] in ("b", "d"):
            cur = {"kind": f[0], "t": float(f[1]) * 1e-6, "mu_p": float(f[2]) if f[0] == "b" else 0.0, "imgs": []}
            steps.append(cur)
        elif f[0] == "i":
            if cur is None:
                raise ConfigError(str(path), f"line {k}", line, "an image line after a b or d line")
            cur["imgs"].append(base / f[1])
    return {"bits": bits, "steps": steps, "source": str(path)}


def _img(p: Path) -> np.ndarray:
    a = mpimg.imread(str(p))
    return np.asarray(a * 255.0 if a.dtype != np.uint8 else a, float)


def measure_steps(desc: dict) -> dict:
    """Temporal pairs: mean and temporal variance per step (bright and dark)."""
    out = {"b": [], "d": []}
    for s in desc["steps"]:
        if len(s["imgs"]) != 2:
            continue   # spatial stacks are not temporal pairs
        a, b = _img(s["imgs"][0]), _img(s["imgs"][1])
        out[s["kind"]].append((s["t"], s["mu_p"], 0.5 * (a.mean() + b.mean()), 0.5 * np.var(a - b)))
    return {k: np.array(v) for k, v in out.items()}


def nominal_fit(m: dict, full_scale: float) -> dict:
    t, mu_p, mu, var = m["b"].T
    td, _, mud, vard = m["d"].T
    dark = np.interp(t, td, mud)
    dark_var = np.interp(t, td, vard)
    i_sat = int(np.argmax(var))
    mu_sat = mu[i_sat]
    lin = (mu - dark) <= 0.7 * (mu_sat - dark)
    K = np.polyfit(mu[lin] - dark[lin], var[lin] - dark_var[lin], 1)[0]
    R = np.polyfit(mu_p[lin], mu[lin] - dark[lin], 1)[0]
    D = np.polyfit(td, mud, 1)[0]
    return {"K_DN_per_e": float(K), "R_DN_per_photon": float(R), "eta": float(R / K),
            "dark_DN": float(mud.mean()), "dark_current_DN_per_s": float(D),
            "sigma_dark_DN": float(np.sqrt(vard.mean())), "sigma_d_e": float(np.sqrt(max(vard.mean() - 1 / 12, 0)) / K),
            "mu_sat_DN": float(mu_sat), "full_scale_DN": full_scale,
            "mu_e_sat": float((mu_sat - mud.mean()) / K), "snr_max_dB": float(20 * np.log10(np.sqrt((mu_sat - mud.mean()) / K)))}


def _mean_model(mu_p, t, nom, effect=None, p=()):
    mu_d, R, fs = nom["dark_DN"], nom["R_DN_per_photon"], nom["full_scale_DN"]
    sig = R * mu_p
    if effect == "nonlinearity":
        sig = sig * (1 - p[0] * sig)
    if effect == "dark_current":
        mu_d = mu_d + p[0] * t
    x = mu_d + sig
    if effect == "soft_saturation":
        s = np.sqrt((p[0] * sig) ** 2 + nom["K_DN_per_e"] * sig + nom["sigma_dark_DN"] ** 2)
        z = (fs - x) / s
        # E[min(X, fs)] for X ~ N(x, s^2)
        return x - s * (norm.pdf(z) - z * (1 - norm.cdf(z)))
    return np.minimum(x, fs)


CANDIDATES = {"nonlinearity": ([1e-4], [0.0], [1e-2]), "soft_saturation": ([0.02], [0.0], [0.5]),
              "dark_current": ([0.0], [-1e3], [1e3])}


def analyse(folder) -> dict:
    desc = read_descriptor(folder)
    m = measure_steps(desc)
    fs = 2 ** desc["bits"] - 1
    nom = nominal_fit(m, float(fs))
    t, mu_p, mu, var = m["b"].T
    train = np.arange(mu.size) % 2 == 0
    test = ~train
    keep = mu < fs - 0.5     # fully clipped steps carry no information on the response
    pred0 = _mean_model(mu_p, t, nom)
    resid = mu - pred0
    frac = (mu - nom["dark_DN"]) / (nom["mu_sat_DN"] - nom["dark_DN"])
    where = []
    for lo, hi in ((0, 0.1), (0.1, 0.7), (0.7, 0.9), (0.9, 1.0), (1.0, 2.0)):
        sel = (frac >= lo) & (frac < hi)
        if sel.any():
            k_pred = nom["sigma_dark_DN"] ** 2 + nom["K_DN_per_e"] * np.maximum(mu[sel] - nom["dark_DN"], 0)
            where.append({"region": f"{lo * 100:.0f}-{hi * 100:.0f} % of saturation", "n": int(sel.sum()),
                          "mean_resid_DN": float(resid[sel].mean()),
                          "rms_resid_DN": float(np.sqrt(np.mean(resid[sel] ** 2))),
                          "var_resid_rel": float(np.mean(var[sel] / k_pred - 1))})
    ranking = [{"effect": "none", "heldout_rms_DN": float(np.sqrt(np.mean(resid[test & keep] ** 2))), "params": {}}]
    for name, (x0, lo, hi) in CANDIDATES.items():
        f = (lambda p, name=name: _mean_model(mu_p[train & keep], t[train & keep], nom, name, p) - mu[train & keep])
        r = least_squares(f, x0, bounds=(lo, hi))
        pred = _mean_model(mu_p, t, nom, name, r.x)
        ranking.append({"effect": name, "params": dict(zip(["value"], r.x.tolist())),
                        "heldout_rms_DN": float(np.sqrt(np.mean((pred - mu)[test & keep] ** 2))),
                        "heldout_max_DN": float(np.max(np.abs(pred - mu)[test & keep]))})
    ranking.sort(key=lambda x: x["heldout_rms_DN"])
    before = ranking[[x["effect"] for x in ranking].index("none")]["heldout_rms_DN"]
    best = ranking[0]
    return {"dataset": desc["source"], "n_bright_steps": int(mu.size), "n_dark_steps": int(m["d"].shape[0]),
            "nominal": nom, "where": where, "ranking": ranking, "best": best["effect"],
            "gap_before_rms_DN": before, "gap_after_rms_DN": best["heldout_rms_DN"],
            "shrink_frac": 1 - best["heldout_rms_DN"] / before,
            "dark_level_spread_DN": float(np.ptp(m["d"][:, 2]))}
