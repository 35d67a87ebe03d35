"""Conversion gain, full well and image lag of a pixel read with true CDS (``circuits.cds``).

Two decks, each one run:

- the *ladder*: a dark pixel and one pixel per charge of ``LADDER`` (electrons in the experiment's
  window, 100 e- to 1 Me-), each on its own column, one flush frame then the window. The largest
  CDS output is the saturated one; the largest ladder signal below 30 % of it (and above 5 mV)
  gives a first conversion gain, hence a first full well: ``fw_est = V_sat / CG_est``.
- the *lag deck*: flush, window, window again: a dark pixel (dark, dark), a small signal
  (``experiment.small_fraction`` of ``fw_est``, then dark) and a bright one
  (``experiment.lag_fraction`` of ``fw_est``, then dark). The small signal against the dark pixel
  in the window frame is the conversion gain; the bright pixel's second frame against the dark
  pixel's is the image lag, in % of the bright frame's signal.

Nothing here knows the pixel's circuit: a designer's netlist is measured as the 4T generator's.
"""
from __future__ import annotations

from ..constants import Q
from ..errors import PixelkitError
from .run import run

#: electrons in the window of the ladder's pixels
LADDER = (100.0, 300.0, 1e3, 3e3, 1e4, 3e4, 1e5, 3e5, 1e6)
#: the linear part of the ladder: above this signal (V) and below this share of the saturated one
LINEAR = (5e-3, 0.3)


def _bench(design, exposures, currents, title, draw, backend):
    from ..circuits.cds import cds_bench, timing_of
    from ..measure.cds import cds
    net = cds_bench(design, design.cell(), exposures, currents, title=title)
    (r,) = run([net], design, draw, backend)
    tm, st = timing_of(design), net.meta["frames"]["starts"]
    return [[cds(r, tm, exposures, st, k, f) for f in range(len(exposures))] for k in range(len(currents))], r, net


def flush_exposure(design) -> float:
    from ..circuits.cds import timing_of
    return timing_of(design).frame(0.0).min_exposure


def current_for(design, electrons: float, t_exp: float) -> float:
    """The photocurrent (A) that puts ``electrons`` into a frame of exposure ``t_exp`` (its light window)."""
    from ..circuits.cds import timing_of
    return electrons * Q / timing_of(design).frame(t_exp).light_time


def ladder(design, draw=None, backend: str = "batch") -> dict:
    tw, t0 = design.experiment.t_window, flush_exposure(design)
    cur = [[0.0, 0.0]] + [[0.0, current_for(design, n, tw)] for n in LADDER]
    out, _r, _n = _bench(design, [t0, tw], cur, "role_ladder", draw, backend)
    dark = out[0][1]
    sig = [row[1] - dark for row in out[1:]]
    v_sat = max(sig)
    lin = [(n, v) for n, v in zip(LADDER, sig) if LINEAR[0] < v < LINEAR[1] * v_sat]
    if not lin:
        raise PixelkitError("the pixel's CDS output has no linear part on the ladder "
                            f"({', '.join(f'{n:g} e-: {1e3 * v:.4g} mV' for n, v in zip(LADDER, sig))}): "
                            "no conversion gain to measure (is the light mapped onto the photodiode?)")
    n, v = lin[-1]
    return {"electrons": list(LADDER), "signal_V": sig, "dark_V": dark, "v_sat_V": v_sat,
            "cg_est_V_per_e": v / n, "fw_est_e": v_sat / (v / n)}


def lag_run(design, draw=None, backend: str = "batch"):
    """The lag deck (module docstring), its charges set from the nominal ladder's full-well estimate
    (the same charges for every Monte Carlo draw): (CDS outputs [pixel][frame], result, netlist, ladder)."""
    lad = ladder(design, None, backend)
    ex = design.experiment
    tw, t0 = ex.t_window, flush_exposure(design)
    n_small, n_bright = ex.small_fraction * lad["fw_est_e"], ex.lag_fraction * lad["fw_est_e"]
    cur = [[0.0, 0.0, 0.0], [0.0, current_for(design, n_small, tw), 0.0], [0.0, current_for(design, n_bright, tw), 0.0]]
    out, r, net = _bench(design, [t0, tw, tw], cur, "role_lag", draw, backend)
    return out, r, net, {**lad, "small_e": n_small, "bright_e": n_bright}


def lag_deck(design, draw=None, backend: str = "batch") -> dict:
    (d, s, b), _r, _n, lad = lag_run(design, draw, backend)
    n_small = lad["small_e"]
    cg = (s[1] - d[1]) / n_small
    bright = b[1] - d[1]
    return {"small_e": n_small, "bright_e": lad["bright_e"], "cg_V_per_e": cg, "bright_V": bright,
            "lag_V": b[2] - d[2], "lag_frac": (b[2] - d[2]) / bright, "lag_e": (b[2] - d[2]) / cg,
            "small_lag_e": (s[2] - d[2]) / cg, "dark_V": d[1], "ladder": lad}


def signal(design, draw=None, backend: str = "batch") -> dict:
    """Conversion gain (V/e-) and the saturated CDS output (V) of this draw."""
    lag = lag_deck(design, draw, backend)
    lad = ladder(design, draw, backend) if draw is not None else lag["ladder"]
    return {"cg_V_per_e": lag["cg_V_per_e"], "v_sat_V": lad["v_sat_V"], "full_well_e": lad["v_sat_V"] / lag["cg_V_per_e"],
            "ladder": lad, "small_e": lag["small_e"]}


def lag(design, draw=None, backend: str = "batch") -> dict:
    r = lag_deck(design, draw, backend)
    return {k: r[k] for k in ("lag_frac", "lag_e", "bright_e", "bright_V", "lag_V", "small_lag_e")}

