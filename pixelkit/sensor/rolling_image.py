"""Rolling-shutter images of a moving rectangle, by time-stepped exposure (``exposure``).

Units as in ``rolling``: rows, columns, line times. The sensor is an electronic
rolling shutter whose accumulation is ``window`` line times (a rolling readout
is the case window = frame). The rectangle's centre passes the sensor's centre
at the moment the centre row is half-way through its accumulation, so the two
opposite-scanning sensors of the compensation see the same object at the same
times (synchronous frames).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .exposure import Cells, Rect, expose, step_for
from .profile import trapezoid
from .rolling import check
from .timing import ShutterTiming

PAD = 6


@dataclass(frozen=True)
class Frame:
    image: np.ndarray        # rows x cols, line times of full coverage
    rect: Rect
    scan: str
    window: float
    t_centre: float          # when the object's centre is at the sensor's centre
    windows: np.ndarray      # rows x 2: each row's accumulation

    def true_centre_row(self) -> float:
        """Where the object's centre is when the row there is half-way through its accumulation.

        Row i (centre i + 0.5) is half-way at m(y) = a + b y (linear in y); the
        object's centre is at y_c0 + v t, so y = y_c0 + v (a + b y).
        """
        mid = self.windows.mean(axis=1)
        b, a = np.polyfit(np.arange(mid.size) + 0.5, mid, 1)
        yc0 = self.rect.y0 + self.rect.height / 2
        return float((yc0 + self.rect.vy * a) / (1 - self.rect.vy * b))


def _layout(h, l, window, s, direction):
    if direction == "right":
        return int(math.ceil(h)) + 2 * PAD, int(math.ceil(l + s * (window + h))) + 2 * PAD
    return int(math.ceil((h + s * window) / (1 - s))) + 2 * PAD, int(math.ceil(l)) + 2 * PAD


def simulate(h: float, window: float, s: float, direction: str, scan: str = "down", l: float = 8.0,
             per_cell: int = 16, shape: tuple[int, int] | None = None, mode: str = "rolling_shutter") -> Frame:
    """One frame of a rectangle h x l moving ``direction`` at s rows (or columns) per line time.

    ``mode = "global"`` exposes every row over the centre row's window (the reference
    the horizontal compensation should reach).
    """
    check(h, window, s, l)
    n_rows, n_cols = shape or _layout(h, l, window, s, direction)
    timing = ShutterTiming("rolling_shutter", n_rows, 1, 1.0, t_int=window,
                           v_blank=max(0, int(math.ceil(window)) - n_rows), scan=scan)
    windows = timing.exposure()
    if mode == "global":      # every row over the centre row's rolling window
        windows = np.tile(windows[n_rows // 2], (n_rows, 1))
    centre_row = n_rows // 2
    t_c = float(windows[centre_row].mean())
    vx, vy = (s, 0.0) if direction == "right" else (0.0, s if direction == "down" else -s)
    yc, xc = n_rows / 2, n_cols / 2
    y0 = round(yc - h / 2) if direction == "right" else yc - h / 2
    rect = Rect(xc - l / 2 - vx * t_c, y0 - vy * t_c, l, h, vx, vy)
    rows, cols = Cells.grid(n_rows), Cells.grid(n_cols)
    image = expose([rect], rows, cols, windows, step_for([rect], rows, cols, per_cell))
    return Frame(image, rect, scan, window, t_c, windows)


def measure_vertical(frame: Frame) -> dict:
    """Total, edge and flat rows of the image along the object's centre column."""
    col = frame.image.shape[1] // 2
    m = trapezoid(frame.image[:, col])
    return {"total_rows": m["total"], "edge_rows": m["edge"], "flat_rows": m["flat"],
            "support_rows": m["support"], "top": m["left"], "bottom": m["right"]}


def row_edges(image: np.ndarray, rows=None) -> dict:
    """Per-row sub-pixel measurements of a horizontally smeared object."""
    peak = image.max()
    rows = np.nonzero(image.max(axis=1) > 0.5 * peak)[0] if rows is None else rows
    ms = [trapezoid(image[r]) for r in rows]
    return {"rows": rows, "left": np.array([m["left"] for m in ms]), "right": np.array([m["right"] for m in ms]),
            "half_left": np.array([m["half_left"] for m in ms]), "half_right": np.array([m["half_right"] for m in ms]),
            "edge": np.array([m["edge"] for m in ms]), "fwhm": np.array([m["fwhm"] for m in ms])}


def measure_horizontal(frame: Frame) -> dict:
    """Row profile, lean (columns per row), border shift and total width of a sideways-moving object."""
    e = row_edges(frame.image)
    rows = e["rows"]
    slope = float(np.polyfit(rows, e["half_left"], 1)[0]) if rows.size > 1 else 0.0
    mid = rows.size // 2
    total_rows = trapezoid(frame.image.max(axis=1))["fwhm"]
    return {"edge_cols": float(np.median(e["edge"])), "row_extent_cols": float(e["right"][mid] - e["left"][mid]),
            "flat_cols": float(np.median(np.maximum(e["fwhm"] - e["edge"], 0))), "shift_per_row": slope,
            "border_shift_cols": slope * total_rows, "total_cols": float(e["right"].max() - e["left"].min()),
            "base_angle_deg": math.degrees(math.atan2(1.0, abs(slope))), "total_rows": total_rows}
