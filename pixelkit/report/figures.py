"""Matplotlib helpers for the report's figures (headless Agg, one style, atomic writes)."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ..fileio import atomic_target, commit  # noqa: E402

plt.rcParams.update({"font.size": 9, "axes.grid": True, "grid.alpha": 0.3, "figure.dpi": 100,
                     "svg.hashsalt": "pixelkit", "savefig.bbox": "tight"})


def axes(n: int = 1, width: float = 8.0, height: float = 3.2, sharex: bool = False):
    fig, ax = plt.subplots(1, n, figsize=(width, height), sharex=sharex, squeeze=False)
    return fig, list(ax[0])


def save(fig, path: Path) -> Path:
    """Write ``fig`` as PNG through a temporary file; deterministic bytes (no timestamp)."""
    path, tmp = atomic_target(path)
    fig.savefig(tmp, format="png", dpi=100, metadata={"Software": None})
    plt.close(fig)
    return commit(path, tmp)
