"""Figures of the frame-level models (PNG, written atomically)."""
from __future__ import annotations

from pathlib import Path

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..fileio import atomic_target, commit  # noqa: E402


def _save(fig, path) -> Path:
    path, tmp = atomic_target(path)
    fig.tight_layout()
    fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return commit(path, tmp)


def _show(ax, img, title, extent=None, cmap="gray", vmax=None):
    ax.imshow(img, cmap=cmap, interpolation="nearest", aspect="auto", extent=extent,
              vmin=0, vmax=vmax if vmax is not None else (img.max() or 1))
    ax.set_title(title, fontsize=8)
    ax.tick_params(labelsize=6)


def rolling_pair(result: dict, path) -> Path:
    """The down- and up-scanning sensors' images, the compensated one (and the global-shutter reference)."""
    fr, n = result["frames"], result["numbers"]
    names = [k for k in ("down_scan", "up_scan", "compensated", "global") if k in fr]
    fig, axes = plt.subplots(1, len(names), figsize=(2.6 * len(names), 3.4))
    vmax = max(fr[k].max() for k in names)
    for ax, k in zip(axes, names):
        _show(ax, fr[k], k.replace("_", " "), vmax=vmax)
    fig.suptitle(f"{n['direction']}, h = {n['h_rows']:g} rows, H = {n['window_rows']:g} rows, "
                 f"s = {n['speed']:g} v_H; compensated h = {n['compensated_h_rows']:.2f}, "
                 f"s = {n['compensated_speed']:.3f}", fontsize=8)
    return _save(fig, path)


def double_exposure(result: dict, path) -> Path:
    """Superposed image (one pixel, two phases), the dual pixel's separated arrays, the trace overlay."""
    im = result["images"]
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.2))
    _show(axes[0], im["superposed"], "superposed (one array, two phases)", vmax=1.0)
    _show(axes[1], im["primary"], "primary array (fraction of swing)", vmax=1.0)
    _show(axes[2], im["secondary"], "secondary array (own scale) + extracted trace")
    tr = result.get("trace")
    if tr:
        axes[2].plot([tr["x_start_px"], tr["x_end_px"]], [tr["row"], tr["row"]], "r-", lw=1.2)
        axes[2].plot([tr["x_start_px"], tr["x_end_px"]], [tr["row"], tr["row"]], "r|", ms=10)
        axes[2].set_xlabel(f"v = {result['speed_kmh']:.1f} km/h (truth {result['truth_kmh']:.1f}, "
                           f"budget +-{result['dv_kmh']:.1f})", fontsize=7)
    return _save(fig, path)


def balance(result: dict, path) -> Path:
    """Low-GSE emulation: scene sharpness, trace contrast and their product against t_int / (t_wait / GSE)."""
    b = result["sweep"]
    r = np.asarray(b["ratio"])
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(10, 3.4))
    ax0.semilogx(r, b["sharpness"], "o-", ms=3, label="scene sharpness (image)")
    ax0.semilogx(r, b["trace_contrast"], "s-", ms=3, label="trace contrast (image)")
    ax0.semilogx(r, b["product"], "k^-", ms=3, label="product")
    ax0.axvline(1.0, color="gray", ls=":")
    ax0.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax0.set_xlabel("t_int / (t_wait / GSE)")
    ax0.legend(fontsize=7)
    ax0.grid(alpha=0.3)
    img = result["image"]
    _show(ax1, img, f"emulated double exposure at t_int = {result['t_int_s'] * 1e3:.3g} ms "
          "(display clipped: the headlight saturates)", vmax=3 * float(np.median(img)))
    return _save(fig, path)
