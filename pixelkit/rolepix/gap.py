"""The sim-to-real gap of a pixel read by role (``pixelkit gap predict | diagnose`` on a 4T or a netlist
pixel): its measured CDS outputs against its SPICE read, and which of the pixel's own effects explains
the difference (docs/gap-diagnosis.md, "A pixel read by role").

**Data.** One row per pixel and frame: ``i_ph_A`` (photocurrent while the frame integrates), ``t_int_s``
(its exposure), ``temp_C``, optionally ``i_ph_prev_A`` (the same pixel in the frame before, at the same
exposure: lag) and, in measured files, ``v_V`` (the true-CDS output, reset sample minus signal sample)
with ``v_std_V`` (its frame-to-frame standard deviation) and ``n_avg`` (frames averaged). Read with the
dual pixel's bounded CSV reader (``gap.data.read_rows``); every problem is listed by row and column.

**Nominal.** Every row is simulated, not interpolated: per (temperature, exposure) one true-CDS bench
(``circuits.cds``) with one column per row, three frames (a flush, the previous frame, the frame read),
the CDS output of the third.

**Effects** (each one parameter, the pixel's own; ``EFFECTS``): ``fd_leakage`` (a current off FD while it
holds the reset level until the signal sample, n_i's temperature law: what CDS does not cancel),
``c_fd`` (capacitance on FD beyond the design's: the conversion gain), and for the 4T generator's PPD
(``families.pixel4t``) ``transfer_barrier`` (the TG-edge barrier raised: transfer-limited lag and
signal loss) and ``pinning_voltage`` (V_pin shifted: the full well). The FD effects need the pixel's
``fd`` probe; a netlist pixel's photodiode is the designer's, so its PPD effects are not candidates.
Each effect is simulated on the same benches at the values of its ``scan``; between them the prediction
is interpolated linearly, row by row. The ``REFINE`` effects of least chi-square on that scan are then
refined in SPICE (a bounded scalar search, each point simulated) between the scan values beside their
best: a transfer barrier's onset is a few tens of mV wide, which no interpolation between scan values
follows.

**Verdict** (``gap.diagnose.verdict_text``'s words), on held-out rows as the dual pixel's: every parameter is
fitted on 70 % of the rows (``gap.diagnose.split``) and the other rows decide (``diagnose``). The nominal read
explains the data when their chi-square over the rows' noise is likely (p >= ``gap.diagnose.P_EXPLAINED``);
else the effect of least held-out chi-square that beats the nominal there is named, and explains them when
that chi-square is likely; effects within ``AMBIGUOUS_DCHI2`` of it are named as
indistinguishable. No test set-up gain or offset is fitted (the CDS output is the pixel's own
difference; a set-up offset would look like FD leakage at one temperature): the data are taken as
calibrated, and docs/gap-diagnosis.md says so. A stated calibration (``Setup``: ``--gain-sd`` /
``--offset-sd``) adds the set-up's gain and offset to every fit, the nominal's included, each a Gaussian
measurement of itself (1 +- gain_sd, 0 +- offset): what is stated is fitted, what is not is calibrated.

**Noise** (``rolepix.gapnoise``): where ``v_std_V`` is a measured frame-to-frame standard deviation
(``n_avg`` >= 2), the result's ``noise`` says whether the nominal read's noise explains it or a share of
FD's kT/C left by the read (``ktc``): kT/C moves no mean, so it is diagnosed on that column alone.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

REQUIRED = ("i_ph_A", "t_int_s", "temp_C")
OPTIONAL = ("i_ph_prev_A", "v_std_V", "n_avg")
#: exposures the benches take (the longest is a long transient)
T_INT_MAX = 0.1


@dataclass(frozen=True)
class Effect:
    name: str
    unit: str
    scan: tuple          # parameter values simulated (SI); 0 is the nominal
    needs: str           # "fd": the cell's FD probe; "ppd": the 4T generator's PPD model
    what: str


EFFECTS = (
    Effect("fd_leakage", "A", (0.0, 2e-12, 1e-11), "fd",
           "a junction leakage off FD (at 25 degC; n_i's temperature law) while it holds between the reset and "
           "the signal sample"),
    Effect("c_fd", "F", (-0.5e-15, 0.0, 0.5e-15, 1e-15, 2e-15, 4e-15), "fd",
           "capacitance on FD beyond the design's (the conversion gain)"),
    Effect("transfer_barrier", "V", (0.0, 0.2, 0.3, 0.35, 0.4, 0.5, 0.6), "ppd",
           "the TG-edge barrier raised (transfer-limited lag and signal loss)"),
    Effect("pinning_voltage", "V", (-0.2, 0.0, 0.1, 0.2), "ppd",
           "the pinning voltage shifted (the full well)"),
)
BY_NAME = {e.name: e for e in EFFECTS}


def candidates(design) -> list:
    """The effects that apply to ``design``'s pixel."""
    cell = design.cell()
    out = []
    for e in EFFECTS:
        if e.needs == "fd" and cell.probe("fd"):
            out.append(e)
        elif e.needs == "ppd" and hasattr(design, "ppd"):
            out.append(e)
    return out


# --- the data -------------------------------------------------------------------------------------
def read(path, design, measured: bool) -> dict:
    """{column: numpy array} of a role gap table (module docstring), validated; DataError listing every
    problem by row and column otherwise."""
    from ..circuits.cds import timing_of
    from ..gap.data import DataError, numeric_column, read_rows, temperature_problem
    header, rows, source = read_rows(path, measured)
    need = REQUIRED + (("v_V", "v_std_V") if measured else ())
    problems = [f"missing column '{c}'" for c in need if c not in header]
    if problems:
        raise DataError(source, problems)
    t_min = timing_of(design).frame(0.0).min_exposure
    out = {}
    for h in (*need, *(c for c in OPTIONAL if c in header)):
        out[h] = numeric_column(h, [r.get(h) for r in rows], h in need, False, problems)
    for i in range(len(rows)):
        for h in ("i_ph_A", "i_ph_prev_A", "v_std_V"):
            if h in out and out[h][i] < 0:
                problems.append(f"row {i + 1}, column '{h}': {out[h][i]:g} is negative")
        if "i_ph_A" in out and out["i_ph_A"][i] > 1e-6:
            problems.append(f"row {i + 1}, column 'i_ph_A': {out['i_ph_A'][i]:g} A is beyond a pixel's photocurrent "
                            "(at most 1 uA)")
        t = out["t_int_s"][i]
        if math.isfinite(t) and not t_min <= t <= T_INT_MAX:
            problems.append(f"row {i + 1}, column 't_int_s': {t:g} s (allowed: {t_min:g} s, the shortest exposure "
                            f"of the design's read, to {T_INT_MAX:g} s)")
        problems += temperature_problem(i, out["temp_C"][i])
        if "n_avg" in out and math.isfinite(out["n_avg"][i]) and (out["n_avg"][i] < 1 or out["n_avg"][i] != int(out["n_avg"][i])):
            problems.append(f"row {i + 1}, column 'n_avg': {out['n_avg'][i]:g} (allowed: a whole number >= 1)")
    if measured and len(rows) < 2:
        problems.append(f"{len(rows)} row: the diagnosis needs at least 2 (its effects are fitted on 70 % of the rows "
                        "and judged on the others)")
    if measured and not problems and np.all(out["v_std_V"] == 0):
        problems.append("column 'v_std_V': every row 0 (the diagnosis weighs rows by their noise)")
    if problems:
        raise DataError(source, problems)
    out.setdefault("i_ph_prev_A", np.zeros(len(rows)))
    out["i_ph_prev_A"] = np.nan_to_num(out["i_ph_prev_A"])
    return out


# --- the SPICE read ------------------------------------------------------------------------------
def _perturbed(design, effect: Effect | None, value: float):
    if effect is None or effect.needs != "ppd" or value == 0.0:
        return design
    p = design.ppd
    key = "barrier" if effect.name == "transfer_barrier" else "v_pin"
    return replace(design, ppd=replace(p, **{key: getattr(p, key) + value}))


def benches(design, table: dict, effect: Effect | None = None, value: float = 0.0, extra=None) -> list:
    """(netlist, row indices) per (temperature, exposure) group: the rows' pixels on one true-CDS bench,
    with ``effect`` at ``value``; ``extra(net, cell)``: a further edit of each netlist (a test's injected
    element)."""
    from ..circuits.cds import cds_bench
    from ..gap.circuit_edits import add_to_subckt
    from ..physics.ppd import dark_scale
    from ..spice.netlist import Element
    from .signal import flush_exposure
    keys = sorted({(float(t), float(x)) for t, x in zip(table["temp_C"], table["t_int_s"])})
    out = []
    for t_c, t_int in keys:
        idx = [i for i in range(len(table["temp_C"])) if table["temp_C"][i] == t_c and table["t_int_s"][i] == t_int]
        d = _perturbed(replace(design, temperature=t_c + 273.15), effect, value)
        cell = d.cell()
        cur = [[0.0, float(table["i_ph_prev_A"][i]), float(table["i_ph_A"][i])] for i in idx]
        net = cds_bench(d, cell, [flush_exposure(d), t_int, t_int], cur,
                        title=f"rolegap_{effect.name if effect else 'nominal'}")
        if effect is not None and effect.needs == "fd" and value != 0.0:
            fd = cell.probe("fd")
            if effect.name == "fd_leakage":
                el = Element("Igapleak", (fd, "0"), value * dark_scale(t_c + 273.15, 298.15, "generation"))
            else:
                el = Element("Cgapfd", (fd, "0"), value)
            net = add_to_subckt(net, cell.subckt.name, el)
        if extra is not None:
            net = extra(net, cell)
        out.append((net, idx))
    return out


def simulate(design, table: dict, effect: Effect | None = None, value: float = 0.0, backend: str = "batch",
             jobs=None, extra=None) -> np.ndarray:
    """The CDS output (V) of every row (the third frame of its bench)."""
    from ..circuits.cds import timing_of
    from ..measure.cds import cds
    from ..spice import simulate_many
    groups = benches(design, table, effect, value, extra)
    results = simulate_many([n for n, _ in groups], backend=backend, jobs=jobs)
    v = np.full(len(table["temp_C"]), np.nan)
    tm = timing_of(design)
    for (net, idx), r in zip(groups, results):
        fr = net.meta["frames"]
        for k, i in enumerate(idx):
            v[i] = cds(r, tm, fr["exposures"], fr["starts"], k, 2)
    return v


# --- the diagnosis -------------------------------------------------------------------------------
#: effects refined in SPICE beyond their scan (the best ones on it), and the simulations each may take
REFINE, REFINE_RUNS = 2, 7


@dataclass(frozen=True)
class Setup:
    """A test set-up's calibration, stated (``--gain-sd`` / ``--offset-sd``): the measured output is
    ``gain v + offset`` of the pixel's, gain 1 +- ``gain_sd``, offset 0 +- ``offset_V``; None: that one is
    taken as calibrated (gain 1, offset 0) and not fitted."""
    gain_sd: float | None = None
    offset_V: float | None = None


def setup_fit(pred, y, sigma, setup: Setup | None):
    """(chi-square, gain, offset) of predictions ``pred`` (points x rows, or rows) against ``y`` with the
    set-up's gain and offset of least chi-square, each stated one a Gaussian measurement of itself (its
    term in the chi-square): weighted least squares in closed form."""
    p = np.atleast_2d(np.asarray(pred, float))
    w = 1.0 / sigma ** 2
    g, o = np.ones(len(p)), np.zeros(len(p))
    fit_g = setup is not None and setup.gain_sd is not None
    fit_o = setup is not None and setup.offset_V is not None
    pg = 1.0 / setup.gain_sd ** 2 if fit_g else 0.0
    po = 1.0 / setup.offset_V ** 2 if fit_o else 0.0
    spp, sp, s1 = (w * p * p).sum(1), (w * p).sum(1), w.sum()
    spy, sy = (w * p * y).sum(1), (w * y).sum()
    if fit_g and fit_o:
        a, b, d = spp + pg, sp, s1 + po
        det = a * d - b * b
        g = ((spy + pg) * d - b * sy) / det
        o = (a * sy - b * (spy + pg)) / det
    elif fit_g:
        g = (spy + pg) / (spp + pg)
    elif fit_o:
        o = (sy - sp) / (s1 + po)
    chi2 = (w * (y - g[:, None] * p - o[:, None]) ** 2).sum(1) + pg * (g - 1.0) ** 2 + po * o ** 2
    return chi2, g, o


def _refine(design, table, effect: Effect, coarse: dict, y, sigma, train, backend, jobs, setup=None) -> dict:
    """``coarse``'s fit searched again between the scan values beside it, every point simulated (the
    chi-square of the fit rows ``train`` only)."""
    from scipy.optimize import minimize_scalar
    xs = np.array(effect.scan)
    k = int(np.clip(np.searchsorted(xs, coarse["value"]), 0, len(xs) - 1))
    lo, hi = xs[max(k - 1, 0)], xs[min(k + 1, len(xs) - 1)]
    seen = {}

    def chi2(x):
        v = simulate(design, table, effect, float(x), backend, jobs)
        seen[float(x)] = v
        return float(setup_fit(v[train], y[train], sigma[train], setup)[0][0])
    r = minimize_scalar(chi2, bounds=(lo, hi), method="bounded",
                        options={"xatol": (hi - lo) / 200, "maxiter": REFINE_RUNS})
    if r.fun >= coarse["chi2"]:
        return coarse
    v = seen[float(r.x)]
    c, g, o = setup_fit(v[train], y[train], sigma[train], setup)
    return {"value": float(r.x), "chi2": float(c[0]), "at_bound": coarse["at_bound"] and r.x in (xs[0], xs[-1]),
            "gain": float(g[0]), "offset_V": float(o[0]), "refined": True, "pred": v}


def _fit(effect: Effect, preds: np.ndarray, y, sigma, train, setup=None) -> dict:
    """The parameter of least chi-square on the fit rows ``train`` (with the stated set-up's gain and offset
    fitted at each), the prediction interpolated linearly between the scan's values; ``pred``: every row's
    prediction at it."""
    xs = np.array(effect.scan)
    grid = np.unique(np.concatenate([np.linspace(a, b, 64) for a, b in zip(xs[:-1], xs[1:])]))
    j = np.clip(np.searchsorted(xs, grid, side="right") - 1, 0, len(xs) - 2)
    w = ((grid - xs[j]) / (xs[j + 1] - xs[j]))[:, None]
    pred = (1 - w) * preds[j] + w * preds[j + 1]           # grid x rows
    chi2, g, o = setup_fit(pred[:, train], y[train], sigma[train], setup)
    k = int(np.argmin(chi2))
    return {"value": float(grid[k]), "chi2": float(chi2[k]), "at_bound": k in (0, len(grid) - 1),
            "gain": float(g[k]), "offset_V": float(o[k]), "pred": pred[k]}


def _judged(fr: dict, y, sigma, test, setup) -> dict:
    """``fr`` (its set-up gain and offset fitted on the fit rows with its parameter) on the held-out rows
    ``test``: their chi-square, plus how far the fitted set-up sits from its stated calibration (the terms
    ``setup_fit`` adds), and the rms residual there."""
    r = y[test] - fr["gain"] * fr["pred"][test] - fr["offset_V"]
    cal = ((fr["gain"] - 1.0) / setup.gain_sd) ** 2 if setup is not None and setup.gain_sd is not None else 0.0
    cal += (fr["offset_V"] / setup.offset_V) ** 2 if setup is not None and setup.offset_V is not None else 0.0
    out = {k: v for k, v in fr.items() if k != "pred"}
    return {**out, "heldout_chi2": float(np.sum((r / sigma[test]) ** 2) + cal),
            "resid_rms_V": float(np.sqrt(np.mean(r ** 2)))}


def diagnose(design, table: dict, backend: str = "batch", jobs=None, setup: Setup | None = None) -> dict:
    """The verdict on held-out rows, as the dual pixel's (``gap.diagnose``): every parameter (the effect's,
    the stated set-up's gain and offset) is fitted on 70 % of the rows (``gap.diagnose.split``, seeded), and
    the other rows decide: the nominal read explains the data when their chi-square is likely; else an
    effect is named only when it lowers their chi-square by more than a fitted parameter can on rows it did
    not see (``chi2_isf(P_BEAT, 1)``), the one of least held-out chi-square, and it explains the gap when
    that chi-square is likely (p >= ``P_EXPLAINED``); effects within ``AMBIGUOUS_DCHI2`` of it there are
    indistinguishable. An effect that fits the fit rows and misses the held-out ones is not explained."""
    from ..gap.diagnose import AMBIGUOUS_DCHI2, P_BEAT, P_EXPLAINED, split, verdict_text
    from ..gap.pvalue import chi2_isf, chi2_sf
    y = table["v_V"]
    n = len(y)
    n_avg = table.get("n_avg", np.ones(n))
    sigma = np.maximum(table["v_std_V"] / np.sqrt(np.nan_to_num(n_avg, nan=1.0)), 1e-7)
    train, test = split(n)
    n_cal = 0 if setup is None else (setup.gain_sd is not None) + (setup.offset_V is not None)
    dof = int(test.sum()) + n_cal
    nominal = simulate(design, table, backend=backend, jobs=jobs)
    c0, g0, o0 = setup_fit(nominal[train], y[train], sigma[train], setup)
    none = _judged({"value": 0.0, "chi2": float(c0[0]), "gain": float(g0[0]), "offset_V": float(o0[0]),
                    "pred": nominal}, y, sigma, test, setup)
    p0 = float(chi2_sf(none["heldout_chi2"], dof))
    fits = {}
    for e in candidates(design):
        preds = np.array([nominal if v == 0.0 else simulate(design, table, e, v, backend, jobs) for v in e.scan])
        fits[e.name] = _fit(e, preds, y, sigma, train, setup)
    for k in (sorted(fits, key=lambda k: fits[k]["chi2"])[:REFINE] if p0 < P_EXPLAINED else ()):
        fits[k] = _refine(design, table, BY_NAME[k], fits[k], y, sigma, train, backend, jobs, setup)
    fits = {k: _judged(f, y, sigma, test, setup) for k, f in fits.items()}
    beat = chi2_isf(P_BEAT, 1)
    for f in fits.values():
        f["p_value"] = float(chi2_sf(f["heldout_chi2"], dof))
        f["heldout_dchi2_vs_nominal"] = none["heldout_chi2"] - f["heldout_chi2"]
        f["beats_nominal"] = bool(f["heldout_dchi2_vs_nominal"] > beat)
    ranking = sorted(fits, key=lambda k: fits[k]["heldout_chi2"])
    winners = [k for k in ranking if fits[k]["beats_nominal"]]
    ambiguous = []
    if p0 >= P_EXPLAINED or not winners:
        best, explained = "none", p0 >= P_EXPLAINED
    else:
        best = winners[0]
        explained = fits[best]["p_value"] >= P_EXPLAINED
        ambiguous = [k for k in winners[1:] if fits[k]["heldout_chi2"] - fits[best]["heldout_chi2"] < AMBIGUOUS_DCHI2]
    chosen = fits[best] if best != "none" else none
    from .gapnoise import diagnose as noise_diagnosis    # kT/C where CDS leaves it: the v_std_V column
    noise = noise_diagnosis(design, table, nominal, backend)
    return {"design": design.name, "n_rows": n, "n_train": int(train.sum()), "n_heldout": int(test.sum()),
            "heldout_rows": [int(i) + 1 for i in np.flatnonzero(test)],
            "candidates": [e.name for e in candidates(design)],
            "noise_rms_V": float(np.sqrt(np.mean(sigma[test] ** 2))),
            "gap_before_rms_V": none["resid_rms_V"], "gap_after_rms_V": chosen["resid_rms_V"],
            "nominal_chi2": none["heldout_chi2"], "nominal_fit_chi2": none["chi2"], "nominal_p_value": p0,
            "best": best, "explained": bool(explained),
            "indistinguishable": ambiguous, "confident": not ambiguous,
            "fits": {k: {**fits[k], "unit": BY_NAME[k].unit, "what": BY_NAME[k].what} for k in ranking},
            "ranking": ranking,
            "verdict": verdict_text(best, explained, ambiguous, False, ranking[0] if ranking else "none"),
            "noise": noise,
            "setup": {"stated": setup is not None, "gain_sd": setup.gain_sd if setup else None,
                      "offset_sd_V": setup.offset_V if setup else None, "gain": chosen["gain"],
                      "offset_V": chosen["offset_V"]}}


def predict(design, table: dict, backend: str = "batch", jobs=None) -> np.ndarray:
    return simulate(design, table, backend=backend, jobs=jobs)

