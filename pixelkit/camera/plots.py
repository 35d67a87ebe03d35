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


def ptc(result: dict, path: Path) -> Path:
    """Temporal variance against mean signal (DN), dark subtracted, per array, with the K line."""
    fig, ax = plt.subplots(figsize=(6, 4))
    for which, r in result.items():
        c, k = r["curves"], r["figures"]["k_dn_per_e"]
        x, y = c["mean_dn"] - c["dark_mean_dn"], c["var_dn"] - c["dark_var_dn"]
        ax.plot(x, y, "o", ms=3, label=f"{which}")
        ax.plot(x, k * x, "-", lw=0.8, label=f"{which}: K = {k:.4g} DN/e-")
    ax.set_xlabel("mean - dark (DN)")
    ax.set_ylabel("variance - dark variance (DN$^2$)")
    ax.set_title("Photon transfer (analytic, EMVA 1288)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return _save(fig, path)


def snr(result: dict, path: Path) -> Path:
    fig, ax = plt.subplots(figsize=(6, 4))
    for which, r in result.items():
        s = r["snr"]
        ax.loglog(s["mu_p"], np.maximum(s["snr"], 1e-3), label=which)
    ax.set_xlabel("photons per pixel")
    ax.set_ylabel("SNR")
    ax.set_title("SNR against exposure")
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
