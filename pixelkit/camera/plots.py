"""Plots of the virtual camera: photon transfer, SNR, noise breakdown."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..fileio import atomic_target, commit  # noqa: E402


def _save(fig, path: Path) -> Path:
    path, tmp = atomic_target(path)
    fig.tight_layout()
    fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return commit(path, tmp)


def data_points(curves: dict) -> tuple[np.ndarray, np.ndarray]:
    """(valid, clipped) masks of an exposure series: a point is clipped beyond saturation (the
    variance maximum, as EMVA 1288 places it: past it the signal clips and its variance collapses,
    which is no noise figure) and non-physical where its variance falls below the dark variance."""
    var = np.asarray(curves["var_dn"], float)
    clipped = np.arange(var.size) > int(np.argmax(var))
    below = (var - np.asarray(curves["dark_var_dn"], float)) <= 0
    below[0] = False   # the first point is the dark level itself
    return ~clipped & ~below, clipped | below


def ptc(result: dict, path: Path) -> Path:
    """Temporal variance against mean signal (DN), dark subtracted, per array, with the K line;
    clipped and non-physical points marked, not drawn as data."""
    fig, ax = plt.subplots(figsize=(6, 4))
    for n, (which, r) in enumerate(result.items()):
        c, k = r["curves"], r["figures"]["k_dn_per_e"]
        x, y = c["mean_dn"] - c["dark_mean_dn"], c["var_dn"] - c["dark_var_dn"]
        ok, bad = data_points(c)
        ax.plot(x[ok], y[ok], "o", ms=3, color=f"C{n}", label=f"{which}")
        ax.plot(x[ok], k * x[ok], "-", lw=0.8, color=f"C{n}", label=f"{which}: K = {k:.4g} DN/e-")
        if bad.any():
            ax.plot(x[bad], y[bad], "x", ms=5, color="0.55",
                    label=f"{which}: beyond saturation or variance below dark ({int(bad.sum())}): not data")
    ax.set_xlabel("mean - dark (DN)")
    ax.set_ylabel("variance - dark variance (DN$^2$)")
    ax.set_title("Photon transfer (analytic, EMVA 1288)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    return _save(fig, path)


def snr(result: dict, path: Path) -> Path:
    """SNR against photons per pixel up to saturation; past it the variance of a clipped signal
    would draw a meaningless rise, so those points are only marked on the saturation line."""
    fig, ax = plt.subplots(figsize=(6, 4))
    for n, (which, r) in enumerate(result.items()):
        s, c = r["snr"], r["curves"]
        mu, val = np.asarray(s["mu_p"], float), np.asarray(s["snr"], float)
        ok, bad = data_points(c)
        ok &= mu > 0
        ax.loglog(mu[ok], np.maximum(val[ok], 1e-3), color=f"C{n}", label=which)
        top = float(np.nanmax(val[ok])) if ok.any() else 1.0
        if bad.any():
            ax.plot(mu[bad & (mu > 0)], np.full(int((bad & (mu > 0)).sum()), top), "x", ms=5, color="0.55",
                    label=f"{which}: clipped exposures (no SNR)")
    ax.set_xlabel("photons per pixel")
    ax.set_ylabel("SNR")
    ax.set_title("SNR against exposure (up to saturation)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    return _save(fig, path)


def noise_breakdown(result: dict, path: Path) -> Path:
    fig, ax = plt.subplots(figsize=(7, 4))
    names = list(next(iter(result.values()))["noise_e"])
    x = np.arange(len(names))
    for k, (which, r) in enumerate(result.items()):
        ax.bar(x + 0.4 * k - 0.2, [r["noise_e"][n] for n in names], width=0.4, label=which)
    ax.set_xticks(x, [n.replace("_", " ") for n in names], rotation=30, ha="right", fontsize=7)
    ax.set_ylabel("input-referred noise (e- rms)")
    ax.set_title("Read-noise breakdown (NCDS, column; afe: the SC AFE's kT/C)")
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=7)
    return _save(fig, path)


def write_all(result: dict, folder: Path) -> list[str]:
    folder = Path(folder)
    return [str(ptc(result, folder / "ptc.png")), str(snr(result, folder / "snr.png")),
            str(noise_breakdown(result, folder / "noise_breakdown.png"))]
