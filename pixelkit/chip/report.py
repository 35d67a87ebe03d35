"""A frame as a tidy table (one row per subpixel, units in the column names) and as images."""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from .frame import KINDS


def frame_table(frame, photo=None) -> str:
    """CSV text: kind,row,col,iph_A,signal_V,reset_level_V[,afe_out_V][,settling_V][,from]; ``from``
    (when some chains were interpolated, ``chip.interp``): spice or interpolated."""
    interp = {r["array"]: set(r["columns"]) for r in frame.interpolated if r["used"]}
    head = ["kind", "row", "col", "iph_A", "signal_V", "reset_level_V"] + (["afe_out_V"] if frame.afe else []) \
        + (["settling_V"] if frame.settling else []) + (["from"] if interp else [])
    buf = io.StringIO()
    buf.write(",".join(head) + "\n")
    for k in KINDS:
        cur = None if photo is None else (photo.iph_p if k == "primary" else photo.iph_s)
        for (r, j), s in np.ndenumerate(frame.signal[k]):
            cells = [k, r, j, "" if cur is None else f"{cur[r, j]:.6g}", f"{s:.7g}",
                     f"{frame.reset_level[k][r, j]:.7g}"]
            if frame.afe:
                cells.append(f"{frame.afe[k][r, j]:.7g}")
            if frame.settling:
                e = frame.settling.get(k)
                cells.append("" if e is None or e[r, j] != e[r, j] else f"{e[r, j]:.4g}")
            if interp:
                cells.append("interpolated" if j in interp.get(k, ()) else "spice")
            buf.write(",".join(map(str, cells)) + "\n")
    return buf.getvalue()


def plot_frame(frame, path: Path, title: str, photo=None, limit: float | None = None) -> Path:
    """Both arrays' double-sampled signals (mV) as images, written atomically; subpixels whose
    settling error is beyond ``limit`` (V) are marked x, clipped ones (``photo``) a square."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from ..fileio import write_atomic
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.2))
    for ax, k in zip(axes, KINDS):
        im = ax.imshow(frame.signal[k] * 1e3, aspect="auto", interpolation="nearest", cmap="gray")
        ax.set_title(f"{k}: signal (mV)")
        _marks(ax, frame, k, photo, limit)
        ax.set_xlabel("column")
        ax.set_ylabel("row")
        fig.colorbar(im, ax=ax)
    for ax in axes:
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="upper right", fontsize=7, framealpha=0.8)
    fig.suptitle(title)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    plt.close(fig)
    return write_atomic(path, buf.getvalue())


def _marks(ax, frame, kind, photo, limit):
    import numpy as np
    lim = limit.get(kind) if isinstance(limit, dict) else limit
    if lim is not None and kind in frame.settling:
        r, c = np.nonzero(np.abs(np.nan_to_num(frame.settling[kind])) > lim)
        if r.size:
            ax.scatter(c, r, marker="x", s=40, color="red", label=f"settling > {lim * 1e3:g} mV")
    sat = None if photo is None or not photo.saturated else photo.saturated.get(kind)
    if sat is not None and sat.any():
        r, c = np.nonzero(sat)
        ax.scatter(c, r, marker="s", s=60, facecolors="none", edgecolors="orange", label="clipped")
