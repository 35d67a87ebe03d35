"""The double exposure emulated on a conventional global-shutter sensor ([Thesis2019] section 2.3).

After the global transfer the charge waits on the storage node until its row is
read; a storage node with finite global shutter efficiency GSE = eta_pd / eta_mem
keeps collecting light at 1/GSE of the photodiode's rate. Row r holds

    S(r) = eta_pd [ integral_0^t_int E dt + (1/GSE) integral_t_int^t_read(r) E dt ]

: a sharp exposure plus a second, attenuated exposure as
long as the row's wait t_wait(r) = t0 + r Row_length / f_pixclk (eq. 2.14). A
bright moving source draws its trace during the wait, so v = d / t_wait (2.15).
The thesis's rule for a good balance (2.16 - 2.18) is equal weight in the two
phases: t_int ~ t_wait / GSE.

Why it matters, measured on the image (``balance``): the scene's sharp part is
the exposure's share of the background, r / (1 + r) with r = t_int / (t_wait / GSE),
and the trace's excess over the background it lies on falls as 1 / (1 + r); a
picture that is both sharp and carries a visible trace wants their product,
largest at r = 1.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from .exposure import Cells, Rect, expose, step_for
from .profile import crossing
from .timing import ShutterTiming
from .trace import background_removed


@dataclass(frozen=True)
class Camera:
    """The thesis's Aptina MT9M021 set-up (table 2.2, eq. 2.18) as defaults."""
    n_rows: int = 960
    row_length: int = 1650
    f_pixclk: float = 22e6
    gse: float = 310.0
    t0: float = 0.0

    def __post_init__(self):
        if not self.gse >= 1:
            raise ConfigError("camera", "gse", self.gse, "a shutter efficiency >= 1 (eta_pd / eta_mem)")

    def timing(self, t_int: float) -> ShutterTiming:
        return ShutterTiming("global", self.n_rows, self.row_length, self.f_pixclk, t_int=t_int, t0=self.t0)

    def t_wait(self, row: int) -> float:
        return self.t0 + row * self.row_length / self.f_pixclk


def rule_of_thumb(camera: Camera, row: int) -> float:
    """t_int ~ t_readout / GSE (eq. 2.17) for the row where the trace starts."""
    return camera.t_wait(row) / camera.gse


def row_profile(camera: Camera, t_int: float) -> np.ndarray:
    """S(r) / S(0) of every row under constant light (1 + t_wait(r) / (GSE t_int))."""
    rows = Cells.grid(camera.n_rows)
    cols = Cells.grid(1)
    img = expose([Rect(-1.0, -1.0, 3.0, camera.n_rows + 2.0)], rows, cols, _windows(camera, t_int, 0, camera.n_rows),
                 dt=camera.row_length / camera.f_pixclk / 4)
    return img[:, 0] / img[0, 0]


def _windows(camera: Camera, t_int: float, first: int, n: int) -> np.ndarray:
    tm = camera.timing(t_int)
    read = tm.read_times()[first:first + n]
    w = np.zeros((n, 2, 3))
    w[:, 0] = (0.0, t_int, 1.0)
    w[:, 1, 0], w[:, 1, 1], w[:, 1, 2] = t_int, read, 1.0 / camera.gse
    return w


X_START = 60.0     # column of the headlight's left edge at t = 0


@dataclass(frozen=True)
class StreetScene:
    """A car (striped body) with a headlight passing in front of a static background, in pixels and seconds."""
    speed_px_s: float = 3700.0       # 50 km/h at 6 m with f = 6 mm and 3.75 um pixels
    stripe_px: float = 4.0           # half-period of the body's texture
    body: tuple = (0.2, 0.6)         # dark and light stripes, relative to the background
    headlight: float = 60.0          # relative to the background
    headlight_px: float = 4.0
    rows: int = 24
    first_row: int = 488             # the band sits around row 500 (eq. 2.18)


def scene_rects(camera: Camera, scene: StreetScene, t_int: float, n_cols: int):
    """Rectangles (relative irradiance), row and column apertures and windows of the emulated frame."""
    u = scene.speed_px_s
    head_y = scene.rows / 2 - scene.headlight_px / 2
    rects = [Rect(-1.0, -1.0, n_cols + 2.0, scene.rows + 2.0, 0.0, 0.0, 1.0),       # static background
             Rect(-5 * n_cols, 0.0, 5 * n_cols + X_START + 2 * scene.headlight_px, scene.rows, u, 0.0,
                  scene.body[0] - 1.0)]
    period = 2 * scene.stripe_px
    travel = u * (t_int + camera.t_wait(scene.first_row + scene.rows))
    for k in range(int((n_cols + travel) / period) + 2):          # the stripes that pass the view
        x = X_START + 2 * scene.headlight_px - (k + 1) * period
        rects.append(Rect(x, 0.0, scene.stripe_px, scene.rows, u, 0.0, scene.body[1] - scene.body[0]))
    rects.append(Rect(X_START, head_y, scene.headlight_px, scene.headlight_px, u, 0.0,
                      scene.headlight - scene.body[0]))
    return rects, Cells.grid(scene.rows), Cells.grid(n_cols), _windows(camera, t_int, scene.first_row, scene.rows)


def image(camera: Camera, scene: StreetScene, t_int: float, n_cols: int = 230) -> dict:
    """The emulated double-exposure image of ``scene`` (relative units), time-stepped."""
    rects, rows, cols, win = scene_rects(camera, scene, t_int, n_cols)
    img = expose(rects, rows, cols, win, step_for(rects, rows, cols, per_cell=8))
    head_y = scene.rows / 2 - scene.headlight_px / 2
    return {"image": img, "head_rows": (int(head_y), int(np.ceil(head_y + scene.headlight_px))),
            "x_start": X_START, "t_wait_s": camera.t_wait(scene.first_row + scene.rows // 2)}


def trace_speed(camera: Camera, scene: StreetScene, t_int: float) -> dict:
    """Speed from the emulated trace, v = d / t_wait (eq. 2.15), against the scene's truth.

    The headlight's sharp image (exposure phase) marks where the path starts
    (its centre); the trace's far end is where the trace falls to half its
    plateau (the source's centre at the row's read).
    """
    r = image(camera, scene, t_int)
    top, bottom = r["head_rows"]
    row = (top + bottom) // 2
    p = background_removed(r["image"], row, bottom - top + 2)
    x = np.arange(p.size) + 0.5
    spot = p > 0.5 * p.max()
    start = float((p[spot] * x[spot]).sum() / p[spot].sum())
    beyond = x > start + 1.5 * scene.headlight_px
    plateau = float(np.median(p[beyond][p[beyond] > 0.25 * p[beyond].max()]))
    end = float(crossing(p * beyond, 0.5 * plateau, from_left=False)) + 0.5
    t_wait = camera.t_wait(scene.first_row + row)
    truth = scene.speed_px_s * (t_wait + t_int / 2)     # centre at mid-exposure -> centre at the read
    return {"trace_px": end - start, "truth_px": truth, "t_wait_s": t_wait,
            "speed_px_s": (end - start) / t_wait, "truth_speed_px_s": scene.speed_px_s}


def metrics(camera: Camera, scene: StreetScene, t_int: float) -> dict:
    """Scene sharpness and trace contrast, both measured on the simulated image."""
    r = image(camera, scene, t_int)
    img = r["image"]
    top, bottom = r["head_rows"]
    far = [i for i in range(img.shape[0]) if i < top - 2 or i >= bottom + 2]
    x0 = int(r["x_start"] + 3 * scene.headlight_px)
    trace_len = scene.speed_px_s * r["t_wait_s"]
    x1 = int(min(img.shape[1] - 2, x0 + 0.8 * trace_len))
    bg = img[far][:, x0:x1].mean(axis=0)
    trace = img[(top + bottom) // 2, x0:x1]
    contrast = float(np.median((trace - bg) / bg))
    tex = img[far, max(0, int(r["x_start"]) - 60):int(r["x_start"]) - 4]
    hi, lo = np.percentile(tex, 95), np.percentile(tex, 5)
    m0 = (scene.body[1] - scene.body[0]) / (scene.body[1] + scene.body[0])
    sharp = float((hi - lo) / (hi + lo) / m0)
    return {"t_int_s": t_int, "ratio": t_int / (r["t_wait_s"] / camera.gse), "sharpness": sharp,
            "trace_contrast": contrast, "image": img}


def balance(camera: Camera = Camera(), scene: StreetScene = StreetScene(),
            ratios=(0.125, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0)) -> dict:
    """Sweep t_int around the rule of thumb; the product of sharpness and trace contrast and its peak."""
    t_rule = rule_of_thumb(camera, scene.first_row + scene.rows // 2)
    from ..progress import progress
    ms = [metrics(camera, scene, k * t_rule) for k in progress(ratios, desc="low-GSE balance sweep", unit="image")]
    prod = np.array([m["sharpness"] * m["trace_contrast"] for m in ms])
    best = int(np.argmax(prod))
    sweep = {"ratio": [m["ratio"] for m in ms], "t_int_s": [m["t_int_s"] for m in ms],
             "sharpness": [m["sharpness"] for m in ms], "trace_contrast": [m["trace_contrast"] for m in ms],
             "product": list(prod / prod.max())}
    return {"t_rule_s": t_rule, "best_ratio": sweep["ratio"][best], "sweep": sweep,
            "image": ms[ratios.index(1.0) if 1.0 in ratios else best]["image"],
            "t_int_s": sweep["t_int_s"][ratios.index(1.0) if 1.0 in ratios else best]}
