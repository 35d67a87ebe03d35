"""HTML section and heatmaps of a gap diagnosis (for the design report)."""
from __future__ import annotations

from pathlib import Path

import jinja2
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..fileio import atomic_target, commit, write_atomic  # noqa: E402
from .nominal import ARRAYS  # noqa: E402

_ENV = jinja2.Environment(loader=jinja2.PackageLoader("pixelkit", "report/templates"),
                          autoescape=jinja2.select_autoescape(["html", "j2"]))


def heatmaps(X, resid, out_dir: Path) -> list[str]:
    names = []
    for k, arr in enumerate(ARRAYS):
        m = X["arr"] == k
        if not m.any():
            continue
        rows, cols = X["row"][m].astype(int), X["col"][m].astype(int)
        ur, uc = np.unique(rows), np.unique(cols)
        grid = np.full((ur.size, uc.size), np.nan)
        for i, r in enumerate(ur):
            for j, c in enumerate(uc):
                sel = (rows == r) & (cols == c)
                if sel.any():
                    grid[i, j] = resid[m][sel].mean() * 1e3
        fig, ax = plt.subplots(figsize=(5, 4))
        im = ax.imshow(grid, aspect="auto", cmap="RdBu_r", origin="lower")
        ax.set_xticks(range(uc.size), [str(c) for c in uc], fontsize=6)
        ax.set_yticks(range(ur.size), [str(r) for r in ur], fontsize=6)
        ax.set_xlabel("column")
        ax.set_ylabel("row")
        ax.set_title(f"{arr}: mean residual (mV) vs nominal")
        fig.colorbar(im, ax=ax)
        fig.tight_layout()
        path, tmp = atomic_target(out_dir / f"gap_heatmap_{arr}.png")
        fig.savefig(tmp, dpi=100, format="png")
        plt.close(fig)
        names.append(commit(path, tmp).name)
    return names


def write_section(result: dict, design_name: str, X, resid, out_dir: Path) -> Path:
    out_dir = Path(out_dir)
    images = heatmaps(X, resid, out_dir)
    r = dict(result)
    r["ranking"] = [dict(row, params_text=_params_text(row["params"])) for row in r["ranking"]]
    html = _ENV.get_template("gap_section.html.j2").render(r=r, design=design_name, images=images)
    return write_atomic(out_dir / "gap_section.html", html)


def _params_text(params: dict) -> str:
    parts = []
    for k, v in params.items():
        if isinstance(v, dict):
            flag = "" if v["identifiable"] else " (not identifiable)"
            parts.append(f"{k} = {v['value']:.3g} [{v['ci95'][0]:.3g}, {v['ci95'][1]:.3g}]{flag}")
        else:
            parts.append(f"{k} = {v:.3g}")
    return "; ".join(parts)
