"""Double-exposure images of a passing car with the dual pixel ([Thesis2019] chapters 2 - 3).

The scene, on the focal plane of the design's optics: a static background whose
photocurrent density is the sizing's background level (``optimize.sizing.light``),
a car body (a fraction of it) and a headlight core (the sizing's headlight
level) moving past at distance c, side view (gamma = 0: image speed v f / c).

- primary array: 24 um cells, the PD (15.1 x 13.55 um) collects; exposure
  [t_s - t_p, t_s] (the arrays' exposures end together at the global transfer);
- secondary array: 8 um wide cells, only the mask opening collects (a small
  square at the cell's centre: the image is point-sampled); exposure [0, t_s];
- superposed: the single-pixel scheme of chapter 2 on the primary geometry, full
  sensitivity over [0, t_p], then the secondary's sensitivity ratio
  (opening / PD area) over [t_p, t_p + t_s].

Charges = exposure integral x photoactive area + dark current x time, plus
temporal noise (shot noise of signal and dark charge, and the kTC of the PD
node's hard reset, which the thesis's non-correlated double sampling keeps;
seeded); signals are fractions of swing through the pixel response of the design's sizing
level (``sizing.level``, ``optimize.levels``: by default the SPICE level, the double-sampled
column signal of the experiment against the collected charge; or the PD node's C(V)), clipped
at full swing. Times and opening: the sizing result at that level by default, or the design
file's own. (The analytic level's fraction is of the PD node's drop over ``pixel.swing``; the
column clips at ground well before it, so on the SPICE level the analytic sizing's background
sits at 0.64 of the column swing instead of 0.5: a SPICE run at the image's photocurrent and
times is the check, ``tests/test_sensor_double_exposure.py``.)
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..constants import Q
from ..errors import ConfigError
from ..physics.dark import dark_current
from ..physics.noise import ktc_electrons
from ..physics.subpixel import figures
from .exposure import Cells, Rect, expose, step_for
from . import speed as sp
from .trace import extract, source_width

TIME_SOURCES = ("sizing", "design")


@dataclass(frozen=True)
class PassingCar:
    speed: float = 50 / 3.6          # m/s
    headlight_size: float = 0.05     # m, the bright core of the lamp
    body_level: float = 0.3          # body / background
    bumper: float = 0.15             # m from the headlight's centre to the car's front
    offset: float = 0.0              # m on the image: where the trace is centred (0 = principal point)

    def __post_init__(self):
        for name in ("speed", "headlight_size", "body_level"):
            if not getattr(self, name) > 0:
                raise ConfigError("passing car", name, getattr(self, name), "a value > 0")


def response_curves(design):
    """The pixel response of the design's sizing level (``optimize.levels.Curves``)."""
    from ..optimize.levels import analytic_curves, spice_curves
    if design.sizing.level == "spice":
        from ..experiments.thesis import run_experiment
        return spice_curves(design, run_experiment(design))
    return analytic_curves(design)


def exposure_times(design, source: str = "sizing", curves=None) -> dict:
    """t_primary, t_secondary and the mask opening: pixelkit's sizing (at the design's sizing
    level, ``curves`` if given) or the design's."""
    if source not in TIME_SOURCES:
        raise ConfigError(design.source, "times", source, f"one of {', '.join(TIME_SOURCES)}")
    if source == "design":
        return {"t_primary_s": design.primary.t_int, "t_secondary_s": design.secondary.t_int,
                "opening_m2": design.secondary.photoactive_area, "source": "design file"}
    from ..optimize.sizing import solve
    r = solve(design, curves or response_curves(design))
    return {"t_primary_s": r["t_int_primary_s"], "t_secondary_s": r["t_int_secondary_s"],
            "opening_m2": r["mask_open_m2"], "source": f"pixelkit sizing ({r['level']} level)"}


def _require(design):
    for sec in ("optics", "scene"):
        if getattr(design, sec) is None:
            raise ConfigError(design.source, sec, None, f"a [{sec}] table for the frame-level scene")


def _grids(design, opening):
    p, s = design.primary, design.secondary
    a = math.sqrt(opening)
    return {"primary": (Cells.grid(p.rows, p.pitch, p.pd_height), Cells.grid(p.cols, p.pitch, p.pd_width)),
            "secondary": (Cells.grid(s.rows, p.pitch, a), Cells.grid(s.cols, s.pitch, a))}


def _scene(design, car: PassingCar, t_mid: float):
    """Moving rectangles (photocurrent density, A/m^2) on the focal plane; x grows with the motion."""
    from ..optimize.sizing import light
    lt = light(design)
    f, c = design.optics.focal_length, design.scene.distance
    u = car.speed * f / c
    width = design.secondary.cols * design.secondary.pitch
    height = design.primary.rows * design.primary.pitch
    w = car.headlight_size * f / c
    xc = width / 2 + car.offset - u * t_mid                 # headlight centre at t = 0
    yc = height / 2
    front = xc + car.bumper * f / c
    body = Rect(front - 10 * width, -height, 10 * width, 3 * height, u, 0.0, (car.body_level - 1) * lt.j_bg)
    head = Rect(xc - w / 2, yc - w / 2, w, w, u, 0.0, lt.j_head - car.body_level * lt.j_bg)
    return [body, head], lt.j_bg, u, w


def _signal(curves, which, charge):
    q, fr = (curves.q_primary, curves.f_primary) if which == "primary" else (curves.q_secondary, curves.f_secondary)
    return np.interp(charge, q, np.maximum.accumulate(fr))   # clipped at full swing beyond the curve


def _noisy(design, geo, q, rng):
    """Charge with shot noise (Poisson) and the PD node's reset kTC (Gaussian), in C."""
    n = np.clip(q / Q, 0, None)
    ktc = ktc_electrons(figures(design, geo)["c_node_F"], design.temperature)
    return (rng.poisson(n) + rng.normal(0.0, ktc, n.shape)) * Q


def render(design, car: PassingCar, times: dict, seed: int | None = 0, curves=None) -> dict:
    """Charges (C) and signals (fraction of swing) of the primary, secondary and superposed images.

    ``seed = None``: noiseless; ``curves``: the pixel response (default ``response_curves``).
    """
    _require(design)
    curves = curves or response_curves(design)
    t_p, t_s, opening = times["t_primary_s"], times["t_secondary_s"], times["opening_m2"]
    rects, j_bg, u, w = _scene(design, car, t_s / 2)
    grids = _grids(design, opening)
    temp = design.temperature
    area = {"primary": design.primary.photoactive_area, "secondary": opening}
    windows = {"primary": [[t_s - t_p, t_s, 1.0]], "secondary": [[0.0, t_s, 1.0]],
               "superposed": [[0.0, t_p, 1.0], [t_p, t_p + t_s, opening / design.primary.photoactive_area]]}
    charges, images = {}, {}
    rng = None if seed is None else np.random.default_rng(seed)
    for name, win in windows.items():
        geo = "secondary" if name == "secondary" else "primary"
        rows, cols = grids[geo]
        sub = getattr(design, geo)
        win_r = np.tile(np.asarray(win, float)[None], (rows.lo.size, 1, 1))
        t_open = sum(b - a for a, b, _ in win)
        open_w = sum((b - a) * k for a, b, k in win)
        e = expose(rects, rows, cols, win_r, step_for(rects, rows, cols))
        i_dark = dark_current(sub.area, sub.perimeter, temp, design.tech.photodiode)
        q = (e + j_bg * open_w) * area[geo] + i_dark * t_open
        if rng is not None:
            q = _noisy(design, geo, q, rng)
        charges[name], images[name] = q, _signal(curves, geo, q)
    return {"charges": charges, "images": images, "grids": grids, "image_speed_m_s": u,
            "headlight_width_m": w, "times": times}


def measure(design, car: PassingCar, times: dict, dc: float = 0.15, seed: int | None = 0, curves=None) -> dict:
    """Speed from the simulated secondary image against the truth, with the eq. 2.6 error budget."""
    r = render(design, car, times, seed, curves)
    f, c = design.optics.focal_length, design.scene.distance
    rows_p, cols_p = r["grids"]["primary"]
    rows_s, cols_s = r["grids"]["secondary"]
    gap = int(math.ceil(r["headlight_width_m"] / 2 / design.primary.pitch)) + 2
    if r["images"]["secondary"].max() >= 0.999:
        raise ConfigError(design.source, "scene.headlight", design.scene.headlight,
                          "a headlight that does not saturate the secondary (the trace cannot be linearised)")
    w_hint = source_width(r["charges"]["primary"], cols_p, gap)
    tr = extract(r["charges"]["secondary"], cols_s, w_hint, gap)
    centre = design.secondary.cols * design.secondary.pitch / 2
    pitch = design.secondary.pitch
    p = sp.from_image(tr["start_m"] - centre, tr["end_m"] - centre, c, 0.0, times["t_secondary_s"], f, pitch, dc=dc)
    budget = sp.error_budget(p)
    pixel_only = sp.error_budget(sp.from_image(tr["start_m"] - centre, tr["end_m"] - centre, c, 0.0,
                                               times["t_secondary_s"], f, pitch, dc=0.0))
    truth_len = r["image_speed_m_s"] * times["t_secondary_s"]
    return {"speed_kmh": budget["v_kmh"], "truth_kmh": car.speed * sp.KMH, "dv_kmh": budget["dv_kmh"],
            "dv_pixel_only_kmh": pixel_only["dv_kmh"], "error_kmh": budget["v_kmh"] - car.speed * sp.KMH,
            "trace_px": tr["length_m"] / pitch, "truth_trace_px": truth_len / pitch,
            "trace_error_px": (tr["length_m"] - truth_len) / pitch,
            "trace": {"row": tr["row"], "x_start_px": tr["start_m"] / pitch - 0.5,
                      "x_end_px": tr["end_m"] / pitch - 0.5},
            "times": times, "images": r["images"]}
