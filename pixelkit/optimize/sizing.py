"""Size the secondary mask opening and both integration times ([Thesis2019] fig. 3.7) with casadi.

Decision variables (log-scaled): the opening A_open, t_primary, t_secondary.
With j = R_eff E the photocurrent density (A/m^2) of the background light at the
sensor and of the headlight spot:

    criterion   f_p(j_bg A_p t_p) = mid,   f_s(j_bg A_open t_s) = low   (5 % / mid-scale)
    motion      v_max t_p f / (Z pitch_p)            <= max_motion_px
    trace       v_min t_s f / (Z pitch_s)            >= min_trace_px
    fov         v_max t_s f / Z                      <= fov_fraction * width_s
    dark        I_dark,s(T_max) t_s                  <= dark_fraction * Q_full,s
    headlight   j_head A_open t_s                    <= Q(headlight_max),  >= snr * Q_noise
                (Q_noise: the NCDS read noise and the headlight's shot noise in quadrature)
    opening     min_opening_side^2 <= A_open <= A_pd
    ratio       t_s = t_ratio t_p                    (when the design fixes it)

every inequality tightened by ``sizing.margin``. Objective ``trace``: the longest
secondary integration (longest trace, best speed accuracy); ``margin``: the
largest common relative slack. Before IPOPT runs, the bounds each constraint puts
on t_s are intersected in closed form, so an infeasible requirement is reported
with the names of the constraints in conflict.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import casadi as ca
import numpy as np

from ..constants import Q
from ..errors import ConfigError, InfeasibleError
from ..physics.dark import dark_current
from ..physics.photo import Spectrum, lux_to_irradiance, responsivity
from .levels import Curves


@dataclass(frozen=True)
class Light:
    j_bg: float      # A/m^2 at the sensor, background
    j_head: float    # A/m^2, headlight spot


def light(design) -> Light:
    sc, op = design.scene, design.optics
    spec = Spectrum.blackbody(sc.spectrum_temperature)
    r_eff = spec.mean(lambda wl: responsivity(wl, design.tech.qe(wl)))
    e_img_lux = sc.reflectance * op.transmission * sc.background / (4 * op.f_number ** 2)
    return Light(r_eff * lux_to_irradiance(e_img_lux, spec), r_eff * sc.headlight)


def _require(design):
    for sec in ("optics", "scene"):
        if getattr(design, sec) is None:
            raise ConfigError(design.source, sec, None, f"a [{sec}] table to size the design")


def _read_noise_e(design, temperature_K: float) -> float:
    """The secondary's temporal read noise (e-) at ``temperature_K``: the NCDS chain of
    ``physics.noise`` (FD kT/C twice through the charge sharing, SF and load), A_sf from
    the SF's operating point."""
    from ..camera.spicenoise import sf_gain
    from ..physics.noise import chain
    from ..techfit.ekv import models_for
    d = replace(design, temperature=temperature_K)
    return chain(d, "secondary", sf_gain(d), models_for(d))["pixel_e"]


class Opening:
    """The secondary's effective opening against its drawn one: the identity (geometric light) or the
    collection model's table (``light.model = "modelled"``, ``layout.pex.lightfigures.opening_table``),
    interpolated linearly in log - log (numbers and casadi expressions alike)."""

    def __init__(self, table: dict | None = None):
        self.table = table
        if table is not None:
            self._la, self._le = np.log(table["drawn_m2"]), np.log(table["effective_m2"])

    @property
    def geometric(self) -> bool:
        return self.table is None

    def __call__(self, a):
        if self.table is None:
            return a
        return float(np.exp(np.interp(np.log(a), self._la, self._le)))

    def casadi(self, la):
        """exp(log A_eff(log a)) for the casadi variable ``la`` = log(a)."""
        if self.table is None:
            return ca.exp(la)
        f = ca.interpolant("aeff", "linear", [self._la], self._le)
        return ca.exp(f(la))


def opening_of(design) -> Opening:
    """The design's opening law: geometric, or the collection model's (computed and cached)."""
    if design.light.model != "modelled":
        return Opening()
    from ..layout.pex.lightfigures import opening_table
    return Opening(opening_table(design))


def _bounds(design, curves: Curves, lt: Light, opening: Opening | None = None):
    """Closed-form bounds on t_p and t_s: {name: (kind, value)} with kind 'lo'/'hi'."""
    d, sc, op, sz = design, design.scene, design.optics, design.sizing
    opening = opening or Opening()
    m = sz.margin
    z, f = sc.distance, op.focal_length
    q_mid = curves.charge_at("primary", d.experiment.mid_fraction)
    q_low = curves.charge_at("secondary", d.experiment.low_fraction)
    t_p = q_mid / (lt.j_bg * d.primary.area)                  # fixed by the criterion
    i_dark = dark_current(d.secondary.area, d.secondary.perimeter, sc.max_temperature, d.tech.photodiode)
    min_open = d.tech.rules.min_opening_side ** 2
    ts = {
        "trace": ("lo", sz.min_trace_px * (1 + m) * z * d.secondary.pitch / (sc.speed_min * f)),
        "fov": ("hi", sz.fov_fraction * (1 - m) * d.secondary.cols * d.secondary.pitch * z / (sc.speed_max * f)),
        "dark": ("hi", sz.dark_fraction * (1 - m) * curves.q_full_secondary / i_dark),
        "opening_max": ("lo", q_low / (lt.j_bg * opening(d.secondary.area))),
        "opening_min": ("hi", q_low / (lt.j_bg * opening(min_open * (1 + m)))),
    }
    tp = {"motion": ("hi", sz.max_motion_px * (1 - m) * z * d.primary.pitch / (sc.speed_max * f)),
          "criterion": ("eq", t_p)}
    q_head = lt.j_head * q_low / lt.j_bg                       # A_open t_s is fixed by the criterion
    q_noise = Q * math.hypot(_read_noise_e(d, sc.max_temperature), math.sqrt(q_head / Q))  # quadrature
    q_head_max = curves.charge_at("secondary", sz.headlight_max)
    checks = {"headlight_max": q_head <= q_head_max * (1 - m),
              "headlight_snr": q_head >= sz.headlight_snr * q_noise * (1 + m)}
    return ts, tp, checks, dict(q_mid=q_mid, q_low=q_low, q_head=q_head, q_head_max=q_head_max,
                                q_noise=q_noise, i_dark=i_dark, min_open=min_open)


def _feasibility(design, ts, tp, checks, opening: Opening | None = None):
    """Collect every conflict the closed-form bounds show; raise once naming them all."""
    conflicts, reasons = [], []
    bad = [name for name, ok in checks.items() if not ok]
    if bad:
        conflicts += bad
        reasons.append("the headlight cannot be shown clearly at this background level")
    if tp["criterion"][1] > tp["motion"][1]:
        conflicts.append("motion")
        reasons.append("the primary cannot reach mid-scale within its motion limit")
    lo = {k: v for k, (kind, v) in ts.items() if kind == "lo"}
    hi = {k: v for k, (kind, v) in ts.items() if kind == "hi"}
    ratio = design.sizing.t_ratio
    if ratio:
        fixed = ratio * tp["criterion"][1]
        broken = [k for k, v in lo.items() if fixed < v] + [k for k, v in hi.items() if fixed > v]
        if broken:
            conflicts += broken + ["t_ratio"]
            reasons.append(f"t_secondary = {ratio:g} x t_primary = {fixed * 1e3:.3g} ms breaks {', '.join(broken)}")
    for a, va in lo.items():
        for b, vb in hi.items():
            if va > vb:
                conflicts += [a, b]
                reasons.append(f"{a} needs t_secondary >= {va * 1e3:.3g} ms, {b} allows <= {vb * 1e3:.3g} ms")
    if conflicts:
        if opening is not None and not opening.geometric:
            lo = opening.table["drawn_m2"][0]
            reasons.append(f"with the collection model's light the secondary collects like an opening of "
                           f"{opening(lo) * 1e12:.3g} um2 when its mask opening is the smallest, {lo * 1e12:.3g} um2 "
                           f"(docs/light-collection.md)")
        raise InfeasibleError("; ".join(reasons), list(dict.fromkeys(conflicts + ["criterion (5 % / mid-scale)"])))


def solve(design, curves: Curves, opening: Opening | None = None) -> dict:
    """Solve the sizing problem at one model level; returns the sized values and checks. ``opening``:
    the secondary's effective opening against the drawn one (default: the design's, ``opening_of``)."""
    _require(design)
    opening = opening if opening is not None else opening_of(design)
    lt = light(design)
    ts, tp, checks, q = _bounds(design, curves, lt, opening)
    _feasibility(design, ts, tp, checks, opening)
    sz, d = design.sizing, design
    t0 = time.perf_counter()
    fp = ca.interpolant("fp", "linear", [curves.q_primary], np.maximum.accumulate(curves.f_primary))
    fs = ca.interpolant("fs", "linear", [curves.q_secondary], np.maximum.accumulate(curves.f_secondary))
    opti = ca.Opti()
    la, ltp, lts = opti.variable(), opti.variable(), opti.variable()
    t_p, t_s = ca.exp(ltp), ca.exp(lts)
    opti.subject_to(fp(lt.j_bg * d.primary.area * t_p) == d.experiment.mid_fraction)
    opti.subject_to(fs(lt.j_bg * opening.casadi(la) * t_s) == d.experiment.low_fraction)
    slack = opti.variable()
    for name, (kind, v) in ts.items():
        if name.startswith("opening"):
            continue
        expr = lts - math.log(v) if kind == "lo" else math.log(v) - lts
        opti.subject_to(expr >= (slack if sz.objective == "margin" else 0))
    opti.subject_to(math.log(tp["motion"][1]) - ltp >= 0)
    opti.subject_to(la >= math.log(q["min_open"] * (1 + sz.margin)))
    opti.subject_to(la <= math.log(d.secondary.area))
    if sz.t_ratio:
        opti.subject_to(lts - ltp == math.log(sz.t_ratio))
    opti.minimize(-slack if sz.objective == "margin" else -lts)
    t_guess = tp["criterion"][1]
    opti.set_initial(ltp, math.log(t_guess))
    opti.set_initial(lts, math.log(t_guess * (sz.t_ratio or 10)))
    a0 = q["q_low"] / (lt.j_bg * t_guess * (sz.t_ratio or 10))
    if not opening.geometric:     # the drawn opening whose effective one is a0
        a0 = float(np.exp(np.interp(math.log(a0), opening._le, opening._la)))
    opti.set_initial(la, math.log(a0))
    opti.set_initial(slack, 0.0)
    opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "sb": "yes", "tol": 1e-10})
    try:
        sol = opti.solve()
    except RuntimeError as exc:
        raise InfeasibleError(f"IPOPT found no solution ({exc})", list(ts) + ["motion", "criterion"]) from None
    solve_time = time.perf_counter() - t0
    a, tpv, tsv = (float(np.exp(sol.value(x))) for x in (la, ltp, lts))
    f, z = design.optics.focal_length, design.scene.distance
    return {
        "level": curves.level,
        "c_m": d.secondary.area / a,
        "mask_open_m2": a,
        "effective_opening_m2": opening(a),
        "light": "geometric" if opening.geometric else "modelled",
        "t_int_primary_s": tpv,
        "t_int_secondary_s": tsv,
        "t_ratio": tsv / tpv,
        "trace_px_at_speed_min": design.scene.speed_min * tsv * f / (z * d.secondary.pitch),
        "trace_px_at_speed_max": design.scene.speed_max * tsv * f / (z * d.secondary.pitch),
        "motion_px_primary": design.scene.speed_max * tpv * f / (z * d.primary.pitch),
        "dark_frac_secondary": q["i_dark"] * tsv / curves.q_full_secondary,
        "headlight_frac": float(fs(q["q_head"])),
        "j_background_A_per_m2": lt.j_bg,
        "solve_time_s": solve_time,
    }
