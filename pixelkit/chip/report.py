"""A frame as a tidy table (one row per subpixel, units in the column names) and as images."""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from .frame import KINDS


def frame_table(frame, photo=None) -> str:
    """CSV text: kind,row,col,iph_A,signal_V,reset_level_V[,afe_out_V]."""
    head = ["kind", "row", "col", "iph_A", "signal_V", "reset_level_V"] + (["afe_out_V"] if frame.afe else [])
    buf = io.StringIO()
    buf.write(",".join(head) + "\n")
    for k in KINDS:
        cur = None if photo is None else (photo.iph_p if k == "primary" else photo.iph_s)
        for (r, j), s in np.ndenumerate(frame.signal[k]):
            cells = [k, r, j, "" if cur is None else f"{cur[r, j]:.6g}", f"{s:.7g}",
                     f"{frame.reset_level[k][r, j]:.7g}"]
            if frame.afe:
                cells.append(f"{frame.afe[k][r, j]:.7g}")
            buf.write(",".join(map(str, cells)) + "\n")
    return buf.getvalue()


def plot_frame(frame, path: Path, title: str) -> Path:
    """Both arrays' double-sampled signals (mV) as images, written atomically."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from ..fileio import write_atomic
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.2))
    for ax, k in zip(axes, KINDS):
        im = ax.imshow(frame.signal[k] * 1e3, aspect="auto", interpolation="nearest", cmap="gray")
        ax.set_title(f"{k}: signal (mV)")
        ax.set_xlabel("column")
        ax.set_ylabel("row")
        fig.colorbar(im, ax=ax)
    fig.suptitle(title)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    plt.close(fig)
    return write_atomic(path, buf.getvalue())
