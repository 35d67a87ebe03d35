"""Readout waveforms of an array simulation (cf. [Thesis2019] fig. 3.13)."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ..fileio import atomic_target, commit  # noqa: E402


def plot_columns(result, columns: dict, path: Path, title: str) -> Path:
    """One axis per group: ``columns = {"primary": [node, ...], "secondary": [...]}``."""
    fig, axes = plt.subplots(len(columns), 1, figsize=(9, 2.6 * len(columns)), sharex=True)
    axes = axes if len(columns) > 1 else [axes]
    t_us = result.time * 1e6
    for ax, (label, nodes) in zip(axes, columns.items()):
        for n in nodes:
            ax.plot(t_us, result[n], lw=0.8, label=n)
        ax.set_ylabel(f"{label} column (V)")
        ax.legend(fontsize=6, ncol=6, loc="lower left")
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time (us)")
    axes[0].set_title(title)
    fig.tight_layout()
    path, tmp = atomic_target(path)
    fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return commit(path, tmp)
