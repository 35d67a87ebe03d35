"""Candidate effects, each in its physical domain, as terms of ``nominal.predict``.

Domains (the term each effect feeds):

- PD charge ``dq`` (passes through PD + FD charge sharing): ``dark_current``,
  ``crosstalk``, ``lag``;
- storage-node charge ``fd`` (on the FD during its hold; the measured response
  of the FD site, ``responses``): ``gse`` (stray light on the FD),
  ``fd_leakage`` (droop with its T law);
- a load on the column during the read (``col_g``, measured, and the load current for a pivot
  elsewhere than the reset level: a load's output conductance pivots near its bias's V_DS): ``sf_gain``;
  the source follower's size (``sf_w``, measured: its current factor; ``c_fd``, measured: the gate
  capacitance an L change puts on FD beyond the width's; its threshold: a level shift of the pixel
  probe, which double sampling cancels): ``sf_strength``;
  the column load's current (``load``, measured): ``column_load`` (the same
  on every column) and ``column_pixel`` (per column: mismatch);
- AFE: ``afe_gain``, the SC stage's gain: C13 larger (``deps``, pivots at the
  reset level, where the SC stage's output is Vref), C11 (measured ``c11``: the
  gain and the column it loads) and the op-amp's DC gain (measured ``a_ol``:
  A_design / A - 1, the gain error and the open-loop gap; to first order it
  and C13 are one gain error, and the fit says when they are not identifiable);
  ``charge_injection`` (coupling from
  the RST clock onto FD and from the AFE's p1 clock onto its virtual ground
  vm, both measured: ``rst_fd``, ``p1_vm``); ``column_afe`` (per column: C11
  and p1 coupling);
- readout light ``readout_light``: a junction photocurrent on the AFE's
  virtual-ground node, junction area x the irradiance, either sign; its
  response (``Nominal.vm_light``, derived in ``nominal``'s docstring) is the
  charge-balance term I t_float / C13 on the AFE probe (t_float: p1 opening to
  the output sample), plus the column kick and the op-amp clamp in the
  non-overlap gap, both measured on the nominal circuit; and on the output
  stage (both probes), either sign;
- readout light while the readout idles ``readout_light_idle``: junction
  photocurrents (area x the irradiance) on the readout's floating nodes - the
  column circuit's sampling node and the AFE's island - from the deck's start,
  split as the layout's light map leaves them open; the nodes float before the
  first row and S1X dumps what they gathered on the column (the light map's
  failure); one figure, the open area; its response is measured
  (``idlelight``). A candidate only when the surrogate carries that table (a
  post-layout view's, built since it was added);
- set-up conditions when the data vary them: ``supply`` (``vdd_V``: supply
  coupling of each probe) and ``settling`` (``f_read_Hz``: incomplete settling
  of the column, a signal loss growing as exp(-t_row / tau)).

Per-column effects (``COLUMN_EFFECTS``) are mismatch drawn around zero: one
value per column of each parameter, with a zero-mean Gaussian prior; the
diagnosis names one only when its column-to-column spread is significant
against its uniform version (``diagnose``).

Stray-light effects scale with the irradiance ``J`` (A/m^2 of photocurrent
density) times the exposed area of their structure, never with the pixel's own
photocurrent. Parameters have physical bounds (measured responses: within
1.5 x the largest amplitude measured); ``scale`` is their typical size (the
fit works in units of it). Temperatures are in degC; 25 degC is the reference
of T-laws.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Param:
    name: str
    lo: float
    hi: float
    scale: float
    x0: float
    starts: tuple = ()     # extra starting values, where the response is not monotone in the parameter


K_B_EV = 8.617333262e-5    # eV/K
T_REF_K = 298.15           # the T laws' reference, 25 degC
# the junction law's free parameters (``_junction``): the diffusion share at 25 degC, the generation's trap offset
# of its activation energy (eV: mid-gap 0; a level off mid-gap raises it), and the voltage dependence of a
# junction current (1/V of the column signal). The depletion width gives ~ (V_R + V_bi)^m with m 1/3 .. 1/2, but
# field-assisted generation (trap-assisted tunnelling, Poole-Frenkel at the high fields of a pinned or heavily doped
# junction) makes it steeper, m up to ~2: dlnI/dV_R = m / (V_R + V_bi) <= 2 / 2.7 V at the PD's 2 V reset, and a PD
# volt is ~0.56 column volt (0.85 V of column signal over the PD's 1.5 V swing), so up to ~1.3 /V of the column
# signal; the bound 1.5 /V. (It was 0.6 /V, the depletion law alone: a PD leak twice as steep - a linear current
# (V + v0) with v0 0.5 - 1 V, development cases 52006 / 52072 - put the fit on the bound.)
DIFF_SHARE = Param("diff_share", 0.0, 1.0, 0.1, 0.2)
DEA = Param("dea_eV", -0.15, 0.25, 0.05, 0.0)
BETA = Param("beta_per_V", 0.0, 1.5, 0.1, 0.0)
# the source follower's small-signal gain A = gm / (gm + gmb + gds) (~0.85) off the model's, and its temperature
# coefficient: a drawn L moves the body effect (short-channel charge sharing lowers the effective gamma) and the
# output conductance (~ 1/L) with it, which the current factor (``sf_w``) and the gate capacitance (``c_fd``) do
# not carry. gmb / gm ~ 0.15 - 0.2 and gds / gm ~ 0.01 - 0.03 here: L 0.6 - 2x the drawn moves A by a few per cent,
# bound +-5 %; the coefficient (phi_F and the mobility's T law move gmb / gm and gds / gm): +-5 % per 100 K.
# Development cases (``ood`` dev, ``sf_wl``): without them 2 of 4 named, 0 explained; with them 4 named, 3 explained.
SF_GAIN = Param("sf_gain_rel", -0.05, 0.05, 1e-2, 0.0)
SF_GAIN_TC = Param("sf_gain_tc_per_100K", -0.05, 0.05, 1e-2, 0.0)
# the floating diffusion's capacitance off the design (F; the ``c_fd`` site's range)
C_FD = Param("c_fd_F", -0.4e-15, 1.0e-15, 1e-16, 0.0)
# the readout-light area's scan (fit._scan): 12 values a decade, both signs, over the bounds
AREA_SCAN = tuple(float(s * v) for s in (-1, 1) for v in np.geomspace(1e-12, 3e-9, 42))
# the idle readout's open area (idlelight): 10 a decade from 0.01 to 1000 um2
IDLE_SCAN = tuple(float(v) for v in np.geomspace(1e-14, 1e-9, 51))


def _junction(X, diff_share, dea):
    """I(T) / I(25 degC) of a reverse-biased junction at each row's temperature: generation (~ n_i, its
    activation energy moved by ``dea`` eV when the trap level lies off mid-gap) and diffusion (~ n_i^2) in the
    share ``diff_share`` at 25 degC; n_i of silicon (``X["ni_rel"]``, ``nominal.features``)."""
    n = X["ni_rel"]
    gen = n * np.exp(-dea / K_B_EV * (1.0 / (X["T"] + 273.15) - 1.0 / T_REF_K))
    return (1.0 - diff_share) * gen + diff_share * n * n


def _self_limited(a, beta, s, k):
    """The charge a junction current collects when it falls with the junction's voltage: ``a`` (C) at the
    reset voltage, less ``beta`` (1/V) per volt the node has fallen - by the signal ``s`` it holds and by half
    the charge's own swing (``k``: V per C): a (1 - beta s) / (1 + beta a k / 2)."""
    return a * (1.0 - beta * s) / (1.0 + beta * a * k / 2.0)


def _gse(X, p):            # light reaching the FD while it holds: 1/GSE of the PD's response, each array's own
    pls = np.where(X["arr"] == 0, p[0], p[1])
    return {"fd": _self_limited(pls * X["J"] * X["a_ref"] * X["t_wait"], p[2], X["signal"], X["fd_k"])}


def _fd_leakage(X, p):     # FD junction leakage while it holds: the junction's T law, voltage dependent
    return {"fd": _self_limited(p[0] * _junction(X, p[1], p[2]) * X["t_wait"], p[3], X["signal"], X["fd_k"])}


def _dark_current(X, p):   # PD dark current over the integration: area and perimeter, each with its junction T law
    # (the area's bulk and the perimeter's STI / surface edge are different junctions: generation, diffusion and
    # trap levels of their own), the primary's current at 25 degC p[0], p[1] of it along the perimeter
    area = np.where(X["arr"] == 0, 1.0, X["area_ratio"])
    perim = np.where(X["arr"] == 0, 1.0, X["perimeter_ratio"])
    law = (1.0 - p[1]) * area * _junction(X, p[2], p[3]) + p[1] * perim * _junction(X, p[5], p[6])
    a = p[0] * law * X["t_int"]
    return {"dq": _self_limited(a, p[4], X["signal"] / 2.0, X["dsdq"])}


def _charge_injection(X, p):  # clock coupling onto FD (RST) and onto the AFE's virtual ground (p1); a larger
    return {"rst_fd": p[0], "p1_vm": p[1], "c_fd": p[2]}   # switch also puts its junction on FD


def _sf_gain(X, p):        # a conductance loading the column during the read, to a pivot dv from the reset level
    # (the measured col_g site pivots at the reset level; the rest of its current, g (v_rst - V_pivot), is a
    # change of the column's pull-down current: the load site, relative to the bias current)
    # a short load's conductance and its mirror's current ratio each drift with temperature (channel-length
    # modulation and DIBL; the ratio: the output's V_DS differs from the reference's): p[2] of g, p[3] of the
    # current, per 100 K from 25 degC (bounds +-100 % and +-5 %: a short device's gds roughly doubles or halves
    # over 100 K; the mirror's ratio moves by per cents). Development cases (``ood`` dev, ``load_gds``): with the
    # SF's gain terms above and without these, 0 of 4 named sf_gain (the level's drift with T went to sf_strength)
    g = p[0] * (1.0 + p[2] * X["dT"] / 100.0)
    return {"col_g": g, "load": -g * p[1] / X["i_bias"] + p[3] * X["dT"] / 100.0}


def _column_load(X, p):    # the column load's current, the same on every column
    return {"load": p[0]}


def _afe_gain(X, p):       # SC stage gain: C13 larger (extra eps), C11 (also the column it loads), op-amp gain
    return {"deps": p[0], "c11": p[1], "a_ol": p[2]}


def _sf_strength(X, p):    # the source follower's size: current factor (W / L, mobility), gate capacitance on FD
    # beyond the width's own, threshold (a level shift), its temperature coefficient off the model's (the
    # levels' measured temperature shift, scaled), and its small-signal gain (body effect and output conductance:
    # ``SF_GAIN``) with that gain's temperature coefficient, on the signal (pivot at the reset level)
    gain = p[4] + p[5] * X["dT"] / 100.0
    return {"sf_w": p[0], "c_fd": p[1], "dv_col": -p[2], "temp_scale": p[3], "dv_pix": gain * X["signal"]}


def _readout_light(X, p):  # junction photocurrent on the AFE's vm (area x irradiance) and the output stage
    return {"i_vm": p[0] * X["J"], "dv_out": p[1] * X["J"]}


def _readout_light_idle(X, p):  # open junctions of the readout's floating nodes, lit while it idles before the row
    return {"i_idle": p[0] * X["J"]}


def _crosstalk(X, p):      # light under the secondary's mask: irradiance x the masked area
    return {"dq": p[0] * X["J"] * X["a_sub"] * X["t_int"] * (X["arr"] == 1)}


def _lag(X, p):            # image lag: a fraction of the previous frame's charge, its traps saturating
    q_sat = p[1] * X["q_max"]
    return {"dq": p[0] * q_sat * -np.expm1(-X["i_prev"] * X["t_int"] / q_sat)}


def _supply(X, p):         # supply coupling: each probe moves with vdd
    return {"dv_col": p[0] * X["dvdd"] * (~X["afe"]), "dv_afe": p[1] * X["dvdd"]}


def _settling(X, p):       # column settling within the sample window (0.3 t_row): signal loss
    return {"dv_pix": -X["signal"] * np.exp(-0.3 / (X["f_read"] * p[0]))}


@dataclass(frozen=True)
class ColumnParam:
    """One per-column parameter: bounds, typical size and the width of its zero-mean prior."""
    name: str
    lo: float
    hi: float
    scale: float
    prior: float


# per-column effects: mismatch drawn around zero, one value per column of each parameter
COLUMN_EFFECTS = {
    "column_pixel": ((ColumnParam("load", -0.3, 0.3, 1e-2, 0.05),), lambda X, p: {"load": p[0]}),
    "column_afe": ((ColumnParam("c11_rel", -0.075, 0.075, 1e-3, 0.01),
                    ColumnParam("p1_vm_F", -3e-15, 3e-15, 1e-16, 1e-15)),
                   lambda X, p: {"c11": p[0], "p1_vm": p[1]}),
}


EFFECTS = {
    "gse": ((Param("pls_primary", 0.0, 0.1, 1e-3, 1e-4), Param("pls_secondary", 0.0, 0.1, 1e-3, 1e-4),
             BETA), _gse),
    "fd_leakage": ((Param("i_fd_A", 0.0, 1e-11, 1e-14, 1e-15), DIFF_SHARE, DEA, BETA), _fd_leakage),
    "dark_current": ((Param("i_d_A", 0.0, 1e-11, 1e-14, 1e-15), Param("perimeter_share", 0.0, 1.0, 0.1, 0.5),
                      DIFF_SHARE, DEA, BETA, Param("perimeter_diff_share", 0.0, 1.0, 0.1, 0.2),
                      Param("perimeter_dea_eV", -0.15, 0.25, 0.05, 0.0)), _dark_current),
    "charge_injection": ((Param("c_rst_fd_F", 0.0, 4.5e-16, 1e-17, 1e-17),
                          Param("c_p1_vm_F", -9e-15, 9e-15, 1e-15, 0.0), C_FD), _charge_injection),
    "sf_gain": ((Param("g_col_S", 0.0, 2.5e-7, 1e-7, 5e-8), Param("pivot_dv_V", -1.5, 1.5, 0.1, 0.0),
                 Param("g_tc_per_100K", -1.0, 1.0, 0.1, 0.0), Param("load_tc_per_100K", -0.05, 0.05, 1e-2, 0.0)),
                _sf_gain),
    "column_load": ((Param("load_rel", -0.3, 0.3, 1e-2, 0.0),), _column_load),
    "afe_gain": ((Param("eps_extra", -0.05, 1.0, 1e-2, 0.0), Param("c11_rel", -0.075, 0.075, 1e-2, 0.0),
                  Param("opamp_gain_loss", 0.0, 45.0, 1.0, 0.0)), _afe_gain),
    "sf_strength": ((Param("sf_w_rel", -0.6, 0.9, 0.1, 0.0), C_FD, Param("dvt_V", -0.2, 0.2, 1e-2, 0.0),
                     Param("tc_rel", -0.5, 0.5, 0.05, 0.0), SF_GAIN, SF_GAIN_TC), _sf_strength),
    # the vm response has the op-amp clamp's steps in the current: the fit scans AREA_SCAN for its starts
    "readout_light": ((Param("a_junction_m2", -3e-9, 3e-9, 1e-11, 0.0, AREA_SCAN),
                       Param("out_V_per_A_m2", -1.0, 1.0, 1e-5, 0.0)), _readout_light),
    "readout_light_idle": ((Param("a_open_m2", 0.0, 1e-9, 1e-12, 0.0, IDLE_SCAN),), _readout_light_idle),
    "crosstalk": ((Param("k_xt", 0.0, 0.5, 1e-3, 1e-4),), _crosstalk),
    "column_pixel": ((), None),   # per-column terms: COLUMN_EFFECTS
    "column_afe": ((), None),
    "lag": ((Param("lag", 0.0, 0.5, 1e-2, 1e-3), Param("q_sat_rel", 0.2, 20.0, 1.0, 10.0)), _lag),
    "supply": ((Param("pixel_V_per_V", -1.0, 1.0, 1e-2, 0.0), Param("afe_V_per_V", -1.0, 1.0, 1e-2, 0.0)), _supply),
    "settling": ((Param("tau_s", 1e-9, 1e-5, 1e-7, 5e-8),), _settling),
}


NAMES = tuple(EFFECTS)

# Each effect's *core*: its parameters with the physical ones silicon may vary held at the textbook value
# (one PLS for both storage nodes and no voltage dependence; a generation-limited junction law with its
# activation energy free, the PD's dark current scaled by its perimeter; lag linear). The diagnosis fits the
# core and the full effect and keeps the one with the lower BIC (training rows), so a law's extra freedom is
# used only where the data ask for it (``diagnose``). core name -> (its parameters, the full parameter vector)
CORE = {
    "gse": ((Param("pls", 0.0, 0.1, 1e-3, 1e-4),), lambda p: [p[0], p[0], 0.0]),
    "fd_leakage": ((Param("i_fd_A", 0.0, 1e-11, 1e-14, 1e-15), DEA), lambda p: [p[0], 0.0, p[1], 0.0]),
    "dark_current": ((Param("i_d_A", 0.0, 1e-11, 1e-14, 1e-15), DEA), lambda p: [p[0], 1.0, 0.0, p[1], 0.0, 0.0, p[1]]),
    "lag": ((Param("lag", 0.0, 0.5, 1e-2, 1e-3),), lambda p: [p[0], 1e6]),
    "sf_gain": ((Param("g_col_S", 0.0, 2.5e-7, 1e-7, 5e-8),), lambda p: [p[0], 0.0, 0.0, 0.0]),
    "sf_strength": ((Param("sf_w_rel", -0.6, 0.9, 0.1, 0.0),), lambda p: [p[0], 0.0, 0.0, 0.0, 0.0, 0.0]),
    "charge_injection": ((Param("c_rst_fd_F", 0.0, 4.5e-16, 1e-17, 1e-17), Param("c_p1_vm_F", -9e-15, 9e-15, 1e-15, 0.0)),
                         lambda p: [p[0], p[1], 0.0]),
}
CORE_SUFFIX = ":core"


def effect(name: str):
    """(parameters, terms function) of a library effect or of its core (``<name>:core``)."""
    if name.endswith(CORE_SUFFIX):
        base = name[:-len(CORE_SUFFIX)]
        params, expand = CORE[base]
        fn = EFFECTS[base][1]
        return params, lambda X, p: fn(X, expand(p))
    return EFFECTS[name]


def base_name(model: str) -> str:
    """The effect a fitted model (``gse:core``, ``gse:core+lag``) names."""
    return "+".join(m.split(":")[0] for m in model.split("+"))


def applicable(X) -> tuple:
    """The candidates the data can say anything about (a factor that never varies cannot be fitted)."""
    out = []
    for name in NAMES:
        if name == "readout_light_idle" and not X.get("has_idle_light"):
            continue
        if name == "lag" and not X["has_prev"]:
            continue
        if name == "supply" and np.ptp(X["dvdd"]) == 0:
            continue
        if name == "settling" and np.ptp(X["f_read"] / X["f_design"]) == 0:
            continue
        if name in ("column_pixel", "column_afe"):
            probe = ~X["afe"] if name == "column_pixel" else X["afe"]
            if any(np.unique(X["col"][probe & (X["arr"] == a)]).size < 2 for a in (0, 1)
                   if (probe & (X["arr"] == a)).any()):
                continue
        out.append(name)
    return tuple(out)
