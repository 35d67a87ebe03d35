"""Exposure engine speed: the matrix-product form against a step-by-step outer-product loop, same process.

Both compute the same image (checked here); the loop is the baseline.

    python benchmarks/sensor.py
"""
from __future__ import annotations

import time

import numpy as np

import common  # noqa: F401  (import path)
from pixelkit.sensor.exposure import Cells, _coverage, expose, step_for
from pixelkit.sensor import lowgse as lg
from pixelkit.sensor.rolling_image import simulate


def loop(rects, rows, cols, windows, dt):
    """One outer product per time step and rectangle (the naive form)."""
    windows = np.asarray(windows, float)
    if windows.ndim == 2:
        windows = np.concatenate([windows, np.ones((windows.shape[0], 1))], axis=1)[:, None, :]
    t0, t1 = windows[..., 0].min(), windows[..., 1].max()
    image = np.zeros((rows.lo.size, cols.lo.size))
    for t in t0 + dt * np.arange(int(np.ceil((t1 - t0) / dt - 1e-9))):
        ov = np.clip(np.minimum(t + dt, windows[..., 1]) - np.maximum(t, windows[..., 0]), 0, None)
        w = (ov * windows[..., 2]).sum(axis=1)
        for r in rects:
            cy = _coverage(rows, np.array([r.y0 + r.vy * (t + dt / 2)]), r.height)[0]
            cx = _coverage(cols, np.array([r.x0 + r.vx * (t + dt / 2)]), r.width)[0]
            image += r.irradiance * np.outer(w * cy, cx)
    return image


def case(label, rects, rows, cols, windows, dt):
    t0 = time.perf_counter()
    base = loop(rects, rows, cols, windows, dt)
    t_loop = time.perf_counter() - t0
    t0 = time.perf_counter()
    fast = expose(rects, rows, cols, windows, dt)
    t_fast = time.perf_counter() - t0
    assert np.allclose(base, fast, atol=1e-9 * fast.max())
    print(f"{label}: loop (baseline) {t_loop * 1e3:8.1f} ms, matrix product {t_fast * 1e3:8.1f} ms "
          f"= {t_fast / t_loop:6.3f} x baseline")


def main():
    for h, window, s, d in ((12.0, 60.0, 0.5, "right"), (12.0, 60.0, 0.8, "down")):
        f = simulate(h, window, s, d, l=10.0)
        rows, cols = Cells.grid(f.image.shape[0]), Cells.grid(f.image.shape[1])
        case(f"rolling {d}, {f.image.shape[0]} x {f.image.shape[1]} px, 1 rectangle", [f.rect], rows, cols,
             f.windows, step_for([f.rect], rows, cols))
    cam, scene = lg.Camera(), lg.StreetScene()
    t_int = lg.rule_of_thumb(cam, 500)
    rects, rows, cols, win = lg.scene_rects(cam, scene, t_int, 230)
    case(f"low-GSE street, {rows.lo.size} x {cols.lo.size} px, {len(rects)} rectangles (2 windows per row)",
         rects, rows, cols, win, step_for(rects, rows, cols, per_cell=8))


if __name__ == "__main__":
    main()
