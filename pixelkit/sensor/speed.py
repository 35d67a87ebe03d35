"""Speed from a trace ([Thesis2019] eq. 2.1 - 2.5) and its error budget (eq. 2.6 - 2.11).

Geometry (pinhole camera, fig. 2.3). The source moves on a straight line at
lateral distance c from the camera; a point of the line seen at angle theta from
the perpendicular dropped on the line lies at c tan(theta) along it. The image
plane makes the angle gamma with the line, so a ray at angle phi from the optical
axis makes gamma - phi with that perpendicular. The trace starts at
alpha = atan(x1 / f) and ends at alpha + beta = atan(x2 / f) on the image
(x from the principal point), so

    d = c (tan(gamma - alpha) - tan(gamma - alpha - beta))        (2.4)
    v = d / t_int                                                  (2.5)

Error propagation (2.6) with the partial derivatives of (2.5):

    dv/dc     = (tan(gamma - alpha) - tan(gamma - alpha - beta)) / t_int = v / c    (2.7)
    dv/dalpha = c (sec^2(gamma - alpha - beta) - sec^2(gamma - alpha)) / t_int      (2.8)
    dv/dbeta  = c sec^2(gamma - alpha - beta) / t_int                                (2.9)
    dv/dt     = -v / t_int

The pixel's angle is dalpha = dbeta = atan(n_px s_pix / f) (n_px = 1 in the
thesis); gamma and the clock are known (1 ns of jitter on 53.6 ms: negligible).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import ConfigError

KMH = 3.6   # (km/h) / (m/s)


@dataclass(frozen=True)
class TracePoint:
    """The thesis's test point (section 2.2.2.4) as defaults; SI units, angles in rad."""
    c: float = 6.0
    gamma: float = math.radians(44.0)
    t_int: float = 53.6e-3
    alpha: float = math.radians(7.4)
    beta: float = math.radians(5.0)
    focal_length: float = 6e-3
    pixel: float = 3.75e-6
    dc: float = 0.15
    dgamma: float = 0.0
    dt: float = 1e-9
    pixel_error_px: float = 1.0

    def __post_init__(self):
        for name, lo in (("c", 0), ("t_int", 0), ("focal_length", 0), ("pixel", 0)):
            if not getattr(self, name) > lo:
                raise ConfigError("trace point", name, getattr(self, name), "a value > 0")
        for name in ("dc", "dgamma", "dt", "pixel_error_px"):
            if getattr(self, name) < 0:
                raise ConfigError("trace point", name, getattr(self, name), "an uncertainty >= 0")
        for name, ang in (("gamma - alpha", self.gamma - self.alpha),
                          ("gamma - alpha - beta", self.gamma - self.alpha - self.beta)):
            if not abs(ang) < math.pi / 2 - 1e-6:
                raise ConfigError("trace point", name, math.degrees(ang),
                                  "an angle between -90 and 90 deg (the ray must meet the line of motion)")


def displacement(p: TracePoint) -> float:
    """d (m), eq. 2.4."""
    return p.c * (math.tan(p.gamma - p.alpha) - math.tan(p.gamma - p.alpha - p.beta))


def speed(p: TracePoint) -> float:
    """v (m/s), eq. 2.5."""
    return displacement(p) / p.t_int


def pixel_angle(p: TracePoint) -> float:
    return math.atan(p.pixel_error_px * p.pixel / p.focal_length)


def error_budget(p: TracePoint) -> dict:
    """Each term of eq. 2.6 (m/s), their root sum of squares and the relative error."""
    v = speed(p)
    sec2 = lambda x: 1.0 / math.cos(x) ** 2  # noqa: E731
    a1, a2 = p.gamma - p.alpha, p.gamma - p.alpha - p.beta
    da = pixel_angle(p)
    terms = {
        "c": v / p.c * p.dc,
        "gamma": p.c * (sec2(a1) - sec2(a2)) / p.t_int * p.dgamma,
        "t_int": -v / p.t_int * p.dt,
        "alpha": p.c * (sec2(a2) - sec2(a1)) / p.t_int * da,
        "beta": p.c * sec2(a2) / p.t_int * da,
    }
    dv = math.sqrt(sum(x * x for x in terms.values()))
    return {"v_ms": v, "dv_ms": dv, "rel_err": dv / v, "terms_ms": terms, "pixel_angle_rad": da,
            "v_kmh": v * KMH, "dv_kmh": dv * KMH}


def from_image(x1: float, x2: float, c: float, gamma: float, t_int: float, focal_length: float,
               pixel: float, **unc) -> TracePoint:
    """The trace point of a trace from x1 to x2 on the image plane (m from the principal point)."""
    a = math.atan(x1 / focal_length)
    b = math.atan(x2 / focal_length) - a
    return TracePoint(c=c, gamma=gamma, t_int=t_int, alpha=a, beta=b, focal_length=focal_length,
                      pixel=pixel, **unc)


def image_position(s: float, c: float, gamma: float, focal_length: float) -> float:
    """Where a point at s along the line (from the perpendicular's foot) appears: x = f tan(gamma - atan(s/c))."""
    return focal_length * math.tan(gamma - math.atan(s / c))
