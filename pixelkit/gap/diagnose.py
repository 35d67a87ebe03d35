"""Diagnose a measured dataset: where the gap lies, which effect explains it, whether it is explained.

Statistics (all on rows the fit did not see, a deterministic 70/30 split):

- noise of each row: ``v_std_V / sqrt(n_avg)`` when the data state it (else the
  scatter of replicated operating points, else unknown), plus the nominal
  surrogate's own rms error against SPICE for that probe;
- a candidate *beats the nominal model* when its chi-square on the held-out
  rows is lower than the nominal model's by more than the (1 - ``P_BEAT``)
  point of a chi-square with k degrees of freedom (k = its parameters: under
  "no effect", fitted parameters cannot improve unseen rows by more than
  that), and its BIC (chi-square + k ln n on the training rows) is lower by
  more than ``BIC_MARGIN``; otherwise the answer is ``none``;
- among those, the held-out chi-square decides (rows the fit did not see: a
  many-parameter candidate, e.g. per-column terms, that absorbs a misspecified
  remainder on the training rows gains nothing there, while BIC's k ln n
  penalty is negligible once chi-square >> n): of the winners within
  ``AMBIGUOUS_DCHI2`` of the lowest held-out chi-square, the lowest BIC (the
  most parsimonious of those the held-out rows cannot tell apart) is named;
  every other candidate whose held-out
  chi-square is within ``AMBIGUOUS_DCHI2`` (3.84, the 95 % point of a chi-square
  with one degree of freedom: a held-out likelihood ratio below 6.8) of it is
  listed as indistinguishable (``gap plan`` proposes the measurement that
  separates them);
- absolute goodness of fit: the held-out chi-square of the named model against
  the stated noise; p < ``P_EXPLAINED`` means the gap is *not explained*, and the
  answer gives the best partial candidate and where the remainder lies;
- the bench's calibration, when stated (``SetupBounds.gain_sd`` / ``offset_sd_V``):
  one more measurement of each set-up gain and offset of a probe in the data. It
  is a term of every fit (``fit``) and of its BIC, and every held-out chi-square
  above adds how far the fit's set-up sits from it (``calibration_chi2``; its
  terms add to the degrees of freedom). Since the fit has seen it, a candidate
  can gain on it what it takes from the set-up: in-sample, at most a chi-square
  with its own parameters, which the (1 - ``P_BEAT``) point already allows.
  Without a calibration, a uniform gain and offset change of one probe's path
  (an op-amp's DC gain a few dB low) is the set-up's own gain and offset within
  their tolerances: the data cannot show it, and the answer says so
  (``calibration``).
"""
from __future__ import annotations

import numpy as np

from .data import check_degenerate
from .effects import COLUMN_EFFECTS, CORE, CORE_SUFFIX, applicable
from .fit import N_SETUP, SetupBounds, calibration_terms, column_keys, evaluate, fit, prediction_sd
from .nominal import features
from .pvalue import chi2_isf, chi2_sf
from .where import breakdown

TRAIN_FRACTION = 0.7
BIC_MARGIN = 10.0
P_BEAT = 1e-3
AMBIGUOUS_DCHI2 = 3.84
P_EXPLAINED = 1e-3
P_SPREAD = 1e-3


def split(n: int, seed: int = 0):
    """Deterministic random split: (train mask, held-out mask)."""
    rng = np.random.default_rng(seed)
    order = rng.permutation(n)
    train = np.zeros(n, bool)
    train[order[: int(round(TRAIN_FRACTION * n))]] = True
    return train, ~train


def _sub(X, m):
    return {k: (v[m] if isinstance(v, np.ndarray) and v.shape == m.shape else v) for k, v in X.items()}


def _rms(x):
    return float(np.sqrt(np.mean(np.square(x)))) if x.size else float("nan")


def noise(table, X, nom) -> tuple[np.ndarray, str]:
    """Per-row standard deviation of the measured value, and where it came from."""
    sur = np.where(X["afe"], nom.error["afe_rms_V"], nom.error["pixel_rms_V"])
    if nom.temp is not None and "temp_pixel_rms_V" in nom.error:   # rows off the design temperature: the table's
        hot = np.asarray(X["dT"]) != 0                                 # own error too
        sur = np.where(hot, np.hypot(sur, np.where(X["afe"], nom.error["temp_afe_rms_V"],
                                                   nom.error["temp_pixel_rms_V"])), sur)
    std = table.columns.get("v_std_V")
    if std is not None and np.all(np.isfinite(std)):
        n_avg = table.columns.get("n_avg")
        n_avg = np.ones_like(std) if n_avg is None else np.where(np.isfinite(n_avg), n_avg, 1.0)
        with np.errstate(over="ignore"):
            return np.sqrt(std ** 2 / n_avg + sur ** 2), "v_std_V / sqrt(n_avg) + surrogate error"
    keys = {}
    y = table.num("v_V")
    for i in range(len(y)):
        k = (X["arr"][i], X["afe"][i], X["i"][i], X["t_int"][i], X["t_wait"][i], X["T"][i], X["col"][i])
        keys.setdefault(k, []).append(y[i])
    groups = [np.array(v) for v in keys.values() if len(v) >= 2]
    if groups and sum(len(g) - 1 for g in groups) >= 5:
        pooled = np.sqrt(sum(np.sum((g - g.mean()) ** 2) for g in groups) / sum(len(g) - 1 for g in groups))
        return np.sqrt(pooled ** 2 + sur ** 2), "replicate scatter + surrogate error"
    return np.full(len(y), np.nan), "unknown (no v_std_V column and no replicated rows)"


def diagnose(design, table, nom, seed: int = 0, candidates=None, setup: SetupBounds = SetupBounds()) -> dict:
    return analyse(design, table, nom, seed, candidates, setup)[0]


def analyse(design, table, nom, seed: int = 0, candidates=None, setup: SetupBounds = SetupBounds()):
    """(result, row features, residual of every row against the calibrated nominal model)."""
    X = features(table, nom, design)
    y = table.num("v_V")
    sigma, noise_src = noise(table, X, nom)
    known = bool(np.all(np.isfinite(sigma)))
    names = applicable(X) if candidates is None else tuple(candidates)
    check_degenerate(table, X, nom, names)
    train, test = split(len(y), seed)
    w = sigma if known else np.ones(len(y))
    Xtr, Xte = _sub(X, train), _sub(X, test)
    cols = np.unique(column_keys(X))
    cal = calibration_terms(setup, X["afe"])
    fits = {"none": fit("none", nom, Xtr, y[train], w[train], setup=setup)}
    spread = {}
    for name in names:
        fits[name] = fit(name, nom, Xtr, y[train], w[train], cols, setup)
        if name in CORE:   # the core law unless the full one earns its parameters: its BIC (training rows) lower
            core = fit(name + CORE_SUFFIX, nom, Xtr, y[train], w[train], cols, setup)   # by the margin an effect
            if core["bic"] <= fits[name]["bic"] + BIC_MARGIN:                             # needs to beat none
                fits[name] = core
        if name in COLUMN_EFFECTS:   # is the column-to-column spread significant? (nested likelihood ratio)
            uni = fit(name, nom, Xtr, y[train], w[train], cols, setup, uniform=True)
            dof = (len(fits[name]["specs"]) - len(uni["specs"]))
            spread[name] = float(chi2_sf(max(uni["chi2"] - fits[name]["chi2"], 0.0), max(dof, 1)))
    resid_te, ranking = {}, []
    for name, fr in fits.items():
        resid_te[name] = evaluate(name, nom, Xte, fr, cols) - y[test]
        fr["heldout_rms_V"] = _rms(resid_te[name])
        fr["heldout_chi2"] = float(np.sum((resid_te[name] / w[test]) ** 2)) + fr["calibration_chi2"]
    none = fits["none"]
    for name, fr in fits.items():
        gain = none["heldout_chi2"] - fr["heldout_chi2"]
        ranking.append({"effect": name, "model": fr["model"], "heldout_rms_V": fr["heldout_rms_V"], "bic": fr["bic"],
                        "heldout_chi2_per_row": fr["heldout_chi2"] / max(int(test.sum()), 1),
                        "train_rms_V": _rms(evaluate(name, nom, Xtr, fr, cols) - y[train]),
                        "n_params": fr["k"] - N_SETUP, "params": _params(name, fr), "setup": fr["setup"],
                        "setup_at_bound": fr["setup_at_bound"], "heldout_dchi2_vs_none": gain,
                        "column_spread_p": spread.get(name), "calibration_chi2": fr["calibration_chi2"],
                        "beats_none": bool(name != "none" and gain > chi2_isf(P_BEAT, max(fr["k"] - N_SETUP, 1))
                                           and none["bic"] - fr["bic"] > BIC_MARGIN
                                           and spread.get(name, 0.0) < P_SPREAD)})
    ranking.sort(key=lambda r: r["bic"])
    winners = [r for r in ranking if r["beats_none"]]
    if winners:
        lowest = min(fits[r["effect"]]["heldout_chi2"] for r in winners)
        near = [r for r in winners if fits[r["effect"]]["heldout_chi2"] - lowest < AMBIGUOUS_DCHI2]
        # of the look-alikes, one that needs the set-up at its tolerance's bound is the weaker reading
        named = next((r for r in near if not r["setup_at_bound"]), near[0])
        winners.remove(named)
        winners.insert(0, named)
    best = winners[0]["effect"] if winners else "none"
    top = next((r["effect"] for r in ranking if r["effect"] != "none"), "none")
    ambiguous = []
    if winners:
        for r in winners[1:]:
            r["heldout_dchi2_vs_best"] = fits[r["effect"]]["heldout_chi2"] - fits[best]["heldout_chi2"]
            if r["heldout_dchi2_vs_best"] < AMBIGUOUS_DCHI2:
                ambiguous.append(r["effect"])
    n_te = int(test.sum())
    dof = n_te + len(cal)
    model, also, pair_tests = best, None, []
    if known and best != "none" and best not in COLUMN_EFFECTS and \
            chi2_sf(_fit_chi2(best, nom, Xte, fits[best], resid_te[best], w[test]), dof) < P_EXPLAINED:
        also, pair_tests = _second_effect(best, names, fits, nom, Xtr, Xte, y[train], y[test], w[train], w[test],
                                          cols, setup, cal)
        if also:
            model = f"{best}+{also}"
    confused = confounded(best, [r["effect"] for r in winners[1:]], X) if best != "none" else []
    fixed = set(fixed_factors(X))
    blind = [(e, sorted(SCALES_WITH[e])) for e in names if e in SCALES_WITH and set(SCALES_WITH[e]) <= fixed
             and e != best]
    for o, _ in confused:
        if o not in ambiguous:
            ambiguous.append(o)
    resid_te.setdefault(model, evaluate(model, nom, Xte, fits[model], cols) - y[test])
    chi2 = _fit_chi2(model, nom, Xte, fits[model], resid_te[model], w[test]) if known else fits[model]["heldout_chi2"]
    p_fit = float(chi2_sf(chi2, dof)) if known else None
    explained = None if not known else bool(p_fit >= P_EXPLAINED)
    resid_none = y - evaluate("none", nom, X, none)
    resid_best = y - evaluate(model, nom, X, fits[model], cols)
    before, after = none["heldout_rms_V"], fits[model]["heldout_rms_V"]
    setup_flag = fits[model]["setup_at_bound"]
    result = {
        "n_rows": int(len(y)), "n_train": int(train.sum()), "n_heldout": n_te, "n_calibration": len(cal),
        "calibration": _calibration(setup, fits[model], cal),
        "candidates": list(names), "noise_source": noise_src,
        "noise_rms_V": float(np.sqrt(np.mean(sigma ** 2))) if known else None,
        "gap_before_rms_V": before, "gap_after_rms_V": after,
        "gap_before_max_V": float(np.max(np.abs(resid_te["none"]))),
        "gap_after_max_V": float(np.max(np.abs(resid_te[model]))),
        "shrink_frac": _shrink(before, after, float(np.sqrt(np.mean(sigma[test] ** 2))) if known else 0.0),
        "shrink_rms_frac": 1.0 - after / before if before > 0 else 0.0,
        "best": best, "also": also, "effects": [best] + ([also] if also else []), "pair_tests": pair_tests,
        "runner_up": top if best == "none" else (winners[1]["effect"] if len(winners) > 1 else None),
        "indistinguishable": ambiguous, "confident": not (ambiguous or blind),
        "fixed_conditions": [FACTOR_NAMES[f] for f in sorted(fixed)],
        "why_indistinguishable": [f"{best} and {o} differ only through the {', '.join(FACTOR_NAMES[f] for f in fs)}, "
                                  f"which these data hold at one value" for o, fs in confused]
        + [f"{e} scales only with the {', '.join(FACTOR_NAMES[f] for f in fs)}, which these data hold at one value: "
           f"what it adds is a constant the test set-up's offset absorbs" for e, fs in blind],
        "cannot_detect": [e for e, _ in blind],
        "explained": explained, "fit_p_value": p_fit, "heldout_chi2_per_row": chi2 / max(n_te, 1),
        "best_partial": (best if best != "none" else top) if explained is False else None,
        "setup_bounds": {"gain_tol": setup.gain_tol, "offset_V": setup.offset_V},
        "setup_at_bound": setup_flag,
        "ranking": ranking,
        "regions": _regions(Xte, y[test], y[test] + resid_te["none"], y[test] + resid_te[model]),
        "probes": probes_moved(Xte, resid_te["none"], resid_te[model], w[test] if known else None),
        "position": position(model),
        "where": breakdown(X, resid_none),
        "remainder_where": _remainder(X, resid_best) if explained is False else [],
        "surrogate_error": nom.error,
        "verdict": verdict_text(model.replace("+", " and "), explained, ambiguous, setup_flag, top)
        + ("; these data cannot show " + ", ".join(e for e, _ in blind) + " (one value of the conditions they scale "
           "with)" if blind else "")
        + ("; the bench's calibration is not stated (--gain-sd / --offset-sd): a gain and offset of one probe's path "
           "within the set-up's tolerances cannot be told from the set-up's own" if model == "none" and not cal else ""),
    }
    return result, X, resid_none


def _fit_chi2(name, nom, Xte, fr, resid, w):
    """The held-out chi-square of the named model against what its prediction can claim: the rows' noise (the
    measurement's and the nominal surrogate's) and the model's own tabulated responses' interpolation error
    (``fit.prediction_sd``), plus its calibration terms. The ranking above uses the noise alone (one yardstick
    for every candidate); this decides whether the named model explains the rows within its stated accuracy."""
    u = prediction_sd(name, nom, Xte, fr)
    return float(np.sum(resid ** 2 / (w ** 2 + u ** 2))) + fr["calibration_chi2"]


# the row quantities each effect's terms scale with (beyond the signal itself): two effects whose lists
# differ only in quantities the data hold fixed cannot be told apart by any fit of these data
SCALES_WITH = {"dark_current": ("t_int", "T"), "fd_leakage": ("t_wait", "T"), "gse": ("t_wait", "J"),
               "crosstalk": ("J", "arr"), "lag": ("i_prev",), "readout_light": ("J", "afe"),
               "charge_injection": ("afe",), "afe_gain": ("afe",), "column_afe": ("col", "afe"),
               "column_pixel": ("col",), "supply": ("dvdd",), "settling": ("f_read",)}
FACTOR_NAMES = {"t_int": "integration time (t_int_s)", "T": "temperature (temp_C)", "t_wait": "wait (t_wait_s)",
                "J": "light level (i_ph_A)", "arr": "array", "afe": "probe", "col": "column",
                "i_prev": "previous frame (i_ph_prev_A)", "dvdd": "supply (vdd_V)", "f_read": "read rate (f_read_Hz)"}


def fixed_factors(X) -> list:
    """The factors the data hold at one value."""
    out = []
    for f in FACTOR_NAMES:
        v = np.asarray(X[f], float)
        if f == "J":
            v = (v > 0).astype(float) + v / max(float(np.max(v)), 1e-30)
        if np.ptp(v) <= 1e-3 * float(np.max(np.abs(v))):   # one value (to 0.1 %: a row time on a 10 ms wait)
            out.append(f)
    return out


def confounded(best, others, X) -> list:
    """[(other effect, [fixed factors])]: the candidates ``best`` differs from only through factors these
    data hold fixed (a T law at one temperature, an integration-time law at one t_int...)."""
    fixed = set(fixed_factors(X))
    out = []
    for o in others:
        diff = set(SCALES_WITH.get(best, ())) ^ set(SCALES_WITH.get(o, ()))
        if diff and diff <= fixed:
            out.append((o, sorted(diff)))
    return out


def _second_effect(best, names, fits, nom, Xtr, Xte, ytr, yte, wtr, wte, cols, setup, cal):
    """A second effect next to ``best`` when ``best`` alone leaves the held-out rows unexplained: each other
    plain candidate is fitted together with it; the pair is kept when its held-out chi-square beats ``best``
    alone by more than the (1 - P_BEAT) point of chi-square(its parameters) and its BIC by ``BIC_MARGIN``
    (nested: the same tests a single effect passes against the nominal) and the two together explain the
    held-out rows (a second effect that only soaks up part of a misfit is not named). The best pair wins."""
    tests, keep = [], None
    for c in names:
        if c in (best, "none") or c in COLUMN_EFFECTS:
            continue
        name = f"{best}+{c}"
        fr = fit(f"{fits[best]['model']}+{fits[c]['model']}", nom, Xtr, ytr, wtr, cols, setup)
        r = evaluate(name, nom, Xte, fr, cols) - yte
        fr["heldout_rms_V"], fr["heldout_chi2"] = _rms(r), float(np.sum((r / wte) ** 2)) + fr["calibration_chi2"]
        gain = fits[best]["heldout_chi2"] - fr["heldout_chi2"]
        ok = bool(gain > chi2_isf(P_BEAT, fr["k"] - fits[best]["k"])
                  and fits[best]["bic"] - fr["bic"] > BIC_MARGIN
                  and chi2_sf(_fit_chi2(name, nom, Xte, fr, r, wte), len(yte) + len(cal)) >= P_EXPLAINED)
        tests.append({"effects": [best, c], "heldout_dchi2_vs_single": gain,
                      "dbic_vs_single": fits[best]["bic"] - fr["bic"],
                      "significant": ok, "params": _params(name, fr), "setup": fr["setup"]})
        if ok and (keep is None or fr["heldout_chi2"] < fits[keep]["heldout_chi2"]):
            fits[name], keep = fr, name
    tests.sort(key=lambda t: -t["heldout_dchi2_vs_single"])
    return (keep.split("+")[1] if keep else None), tests[:5]


def _calibration(setup, fr, cal) -> dict:
    """What the bench's calibration says and how the named model's set-up sits against it."""
    if not cal:
        return {"stated": False, "note": "not stated (--gain-sd / --offset-sd): a uniform gain and offset change "
                f"of one probe's path within +-{setup.gain_tol:.1%} / +-{setup.offset_V * 1e3:g} mV (an op-amp's DC "
                "gain a few dB low) is taken whole by the set-up's own gain and offset: these data cannot show it"}
    return {"stated": True, "gain_sd": setup.gain_sd, "offset_sd_V": setup.offset_sd_V,
            "chi2": fr["calibration_chi2"], "terms": len(cal)}


def _remainder(X, resid):
    """Where the named model's remainder lies: the significant groups, else (a remainder with no pattern in
    any one factor, e.g. column-pair coupling) the groups with the largest mean, each with its p-value."""
    rows = breakdown(X, resid)
    sig = [w for w in rows if w["significant"]]
    return (sig or sorted(rows, key=lambda w: -abs(w["mean_V"])))[:5]


def _shrink(before, after, noise_rms):
    """Fraction of the gap beyond the noise that the named model removes (held-out rows):
    1 - sqrt(after^2 - noise^2) / sqrt(before^2 - noise^2), each excess floored at zero."""
    b = np.sqrt(max(before ** 2 - noise_rms ** 2, 0.0))
    a = np.sqrt(max(after ** 2 - noise_rms ** 2, 0.0))
    return float(1.0 - a / b) if b > 0 else 0.0


def verdict_text(best, explained, ambiguous, setup_flag=False, top="none"):
    """The verdict's words (``gap diagnose``, ``gap emva``): '<effect> explains the gap', 'not explained: the
    best partial candidate is <effect>, a significant remainder stays', 'no effect needed: ...', with the
    candidates the data cannot tell apart."""
    if explained is False:
        name = best if best != "none" else top
        s = f"not explained: the best partial candidate is {name}, a significant remainder stays"
    elif best == "none":
        s = "no effect needed: the nominal model explains the data" + ("" if explained else " (noise not stated)")
    else:
        s = f"{best} explain{'' if ' and ' in best else 's'} the gap"
    if ambiguous:
        s += ("; not a confident name: indistinguishable on these data from " + ", ".join(ambiguous)
              + " (run `gap plan`)")
    if setup_flag:
        s += "; the test set-up gain/offset sits on its plausible bound"
    return s


def _params(name, fr):
    if name in COLUMN_EFFECTS:
        vals, kinds = fr["theta"][N_SETUP:], [spec[0].split("[")[0] for spec in fr["specs"]]
        law = {spec[0]: float(v) for spec, v in zip(fr["specs"], vals) if spec[4] is None}   # the spatial law's
        cols = [k for k in dict.fromkeys(kinds) if not any(n.startswith(k + "[") for n in law)]
        out = {f"{k}_rms": float(np.std(vals[[j == k for j in kinds]])) for k in cols}
        return out | law | {"n_columns": kinds.count(kinds[0])}
    return {spec[0]: iv for spec, iv in zip(fr["specs"], fr["intervals"])}


# where in the chain each effect acts (the probes it can move: a pixel-side effect moves the pixel probe and,
# through the chain, the AFE probe; an AFE-side one the AFE probe alone; the set-up each probe on its own)
POSITION = {"gse": "pixel (storage node)", "fd_leakage": "pixel (storage node)", "dark_current": "pixel (photodiode)",
            "crosstalk": "pixel (photodiode)", "lag": "pixel (photodiode)", "sf_strength": "pixel (source follower)",
            "charge_injection": "pixel (reset switch) and AFE (vm switch)", "sf_gain": "column", "column_load": "column",
            "column_pixel": "column", "settling": "column", "afe_gain": "AFE", "column_afe": "AFE",
            "readout_light": "AFE (and the output stage)", "readout_light_idle": "column sampling node and AFE",
            "supply": "supply", "none": "set-up (each probe's gain and offset)"}


def position(model: str) -> str:
    """Where in the chain the named model's effects act."""
    from .effects import base_name
    return "; ".join(f"{e}: {POSITION.get(e, '?')}" for e in base_name(model).split("+"))


def probes_moved(X, before, after, sigma) -> dict:
    """Per probe on the held-out rows: the gap the nominal model leaves (rms), what the named model leaves, and
    whether the probe moved beyond its noise (the nominal's held-out chi-square there, p < P_EXPLAINED): the
    evidence that places an effect (a chain gain seen at the pixel probe is upstream of the AFE)."""
    out = {}
    for label, m in (("pixel", ~X["afe"]), ("afe", X["afe"])):
        if not m.any():
            continue
        moved = None
        if sigma is not None:
            moved = bool(chi2_sf(float(np.sum((before[m] / sigma[m]) ** 2)), int(m.sum())) < P_EXPLAINED)
        out[label] = {"n": int(m.sum()), "gap_before_rms_V": _rms(before[m]), "gap_after_rms_V": _rms(after[m]),
                      "moved": moved}
    return out


def _regions(X, y, before, after):
    out = []
    for label, m in (("pixel probe", ~X["afe"]), ("afe probe", X["afe"]), ("primary", X["arr"] == 0),
                     ("secondary", X["arr"] == 1)):
        if m.any():
            out.append({"region": label, "n": int(m.sum()), "rms_before_V": _rms(before[m] - y[m]),
                        "rms_after_V": _rms(after[m] - y[m])})
    return out
