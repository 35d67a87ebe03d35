"""The independent image path: a time-stepped exposure of moving rectangles.

Every pixel integrates, over its own exposure windows, the fraction of its
light-collecting aperture that each moving rectangle covers, times the
rectangle's irradiance:

    S[r, c] = sum_rect E_rect * integral_{t in windows(r)} cov_y(r, t) cov_x(c, t) dt

Time is cut into steps of ``dt`` (exact window overlap per step, coverage at the
step's midpoint); rows and columns are separate, so one step is an outer
product and all steps together are one matrix product. Nothing here knows a
closed form: the rolling-shutter sizes, the trace lengths and the compensation
are checked against images made this way.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import PixelkitError


@dataclass(frozen=True)
class Rect:
    """An axis-aligned rectangle moving at constant velocity (position of its top-left corner at t = 0)."""
    x0: float
    y0: float
    width: float
    height: float
    vx: float = 0.0
    vy: float = 0.0
    irradiance: float = 1.0


@dataclass(frozen=True)
class Cells:
    """Light-collecting apertures along one axis: cell i collects over [lo[i], hi[i]]."""
    lo: np.ndarray
    hi: np.ndarray

    @classmethod
    def grid(cls, n: int, pitch: float = 1.0, aperture: float | None = None, origin: float = 0.0) -> "Cells":
        """``n`` cells of ``pitch``; the aperture (default: the whole cell) centred in each."""
        a = pitch if aperture is None else aperture
        if not 0 < a <= pitch:
            raise PixelkitError(f"aperture {a:g} must be > 0 and <= the pitch {pitch:g}")
        centre = origin + (np.arange(n) + 0.5) * pitch
        return cls(centre - a / 2, centre + a / 2)

    @property
    def centre(self) -> np.ndarray:
        return 0.5 * (self.lo + self.hi)


def _coverage(cells: Cells, start: np.ndarray, length: float) -> np.ndarray:
    """Fraction of each aperture covered by [start, start + length] for each time (K x n)."""
    a = start[:, None]
    ov = np.minimum(cells.hi[None, :], a + length) - np.maximum(cells.lo[None, :], a)
    return np.clip(ov, 0.0, None) / (cells.hi - cells.lo)[None, :]


def expose(rects, rows: Cells, cols: Cells, windows: np.ndarray, dt: float, chunk: int = 4096) -> np.ndarray:
    """Integrated irradiance x time (R x C) of ``rects`` seen through per-row ``windows``.

    ``windows`` has shape (R, W, 3): W windows (start, end, weight) per row; a
    weight < 1 models a reduced sensitivity (a closed shutter with finite GSE).
    """
    windows = np.asarray(windows, dtype=float)
    if windows.ndim == 2:
        windows = np.concatenate([windows, np.ones(windows.shape[:1] + (1,))], axis=1)[:, None, :]
    if windows.shape[0] != rows.lo.size or windows.shape[2] != 3:
        raise PixelkitError(f"windows must have shape (rows={rows.lo.size}, W, 3), got {windows.shape}")
    if not dt > 0:
        raise PixelkitError(f"time step {dt!r} must be > 0")
    t0, t1 = float(windows[..., 0].min()), float(windows[..., 1].max())
    dt = min(dt, t1 - t0) if t1 > t0 else 1.0
    n_steps = max(1, int(np.ceil((t1 - t0) / dt - 1e-9)))
    image = np.zeros((rows.lo.size, cols.lo.size))
    chunk = max(16, min(chunk, 4_000_000 // (rows.lo.size * windows.shape[1] + cols.lo.size)))   # bounded memory
    groups: dict = {}                 # rectangles sharing their rows: one matrix product per group
    for r in rects:
        groups.setdefault((r.y0, r.height, r.vy), []).append(r)
    for k0 in range(0, n_steps, chunk):
        tk = t0 + dt * np.arange(k0, min(n_steps, k0 + chunk))
        lo, hi = tk[:, None, None], tk[:, None, None] + dt
        ov = np.clip(np.minimum(hi, windows[None, :, :, 1]) - np.maximum(lo, windows[None, :, :, 0]), 0.0, None)
        w = (ov * windows[None, :, :, 2]).sum(axis=2)            # K x R: weighted time in the row's windows
        mid = tk + dt / 2
        for (y0, height, vy), group in groups.items():
            cy = _coverage(rows, y0 + vy * mid, height)
            cx = sum(r.irradiance * _coverage(cols, r.x0 + r.vx * mid, r.width) for r in group)
            image += (w * cy).T @ cx
    return image


def step_for(rects, rows: Cells, cols: Cells, per_cell: int = 16) -> float:
    """A time step that moves every rectangle at most 1/``per_cell`` of the smallest aperture.

    Without motion any step is exact (inf: one step per window).
    """
    size = min(np.min(rows.hi - rows.lo), np.min(cols.hi - cols.lo))
    v = max([abs(r.vx) for r in rects] + [abs(r.vy) for r in rects] + [0.0])
    return float(size / (per_cell * v)) if v > 0 else float("inf")
