"""kT/C where CDS leaves it: the role gap's noise column (``pixelkit gap diagnose`` on a 4T).

True CDS takes the reset sample and the signal sample of the same reset, so FD's reset noise (kT/C)
cancels and the read noise is a few electrons (``rolepix.noise``). A read that does not (the two samples
of different resets - a reset between them, a "delta" read of a charge stored on FD, a reset that kicks FD
after the reset sample) leaves some or all of it, and that moves no mean: it shows in the frame-to-frame
standard deviation ``v_std_V`` only, which the means' diagnosis (``rolepix.gap``) takes as its weight.
This module reads that column when it is a measured standard deviation (``n_avg`` >= 2 frames on every
row) and asks whether the nominal read's noise explains it, and else whether a share ``s`` of FD's kT/C
does. Per row, at its temperature T (output-referred, V^2):

    var(s) = sigma_read(T)^2 + CG v + s A_sf^2 k T / C_FD

``sigma_read`` the true-CDS read noise of ``.noise`` (``rolepix.noise``), ``CG v`` the signal's shot noise
(v / CG electrons, Poisson; the nominal CDS output v of the row), and FD's kT/C through the follower with
A_sf and C_FD of the 4T's closed form (the design's ``fd_read``: ``families.pixel4t.model``; a netlist pixel
has none, so the effect is not a candidate there). The sample standard deviation of n frames has the standard error
sigma / sqrt(2 (n - 1)) (Gaussian reads; sigma the predicted one, so a row that happens to read low does not
weigh more); chi-square over it: the nominal (s = 0, n rows) is accepted when
p >= ``gap.diagnose.P_EXPLAINED``; else s is fitted in [0, ``S_MAX``] (n - 1 degrees of freedom) and kT/C
explains the noise when that fit is likely. Not modelled: the dark current's shot noise (a fraction of
an electron at the 4T's exposures), the 1/f noise's dependence on the exposure, row / column noise.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..constants import K_B

#: the effect's name in the result, and what it is
KTC = "ktc"
KTC_WHAT = ("FD's reset noise kT/C left in the CDS output (the share of it: 0 true CDS, 1 the two samples of "
            "different resets); seen in the frame-to-frame standard deviation, not in the means")
#: the share's upper bound (a read can leave at most two resets' kT/C: a reset before each sample)
S_MAX = 2.0


def applies(design, table: dict) -> str | None:
    """None when the noise column can be diagnosed, else why not (one sentence)."""
    if not hasattr(design, "fd_read"):
        return "the pixel has no closed form of FD's capacitance (a netlist pixel): kT/C is not a candidate"
    if len(table.get("v_std_V", ())) < 2:
        return ("one row: the share of kT/C is fitted with one degree of freedom, so any standard deviation "
                "would fit it; kT/C needs at least two rows (two signal levels or temperatures)")
    n = table.get("n_avg")
    if n is None or not np.all(np.nan_to_num(n, nan=1.0) >= 2):
        return ("v_std_V is not a measured frame-to-frame standard deviation on every row (n_avg >= 2 frames): "
                "it weighs the means only")
    return None


def parts(design, table: dict, v_nominal: np.ndarray, backend: str = "batch") -> dict:
    """Per row (V^2): the nominal read's variance (read noise + shot noise) and FD's kT/C at the output."""
    from .noise import noise
    from .signal import signal
    nominal, ktc = np.zeros(len(v_nominal)), np.zeros(len(v_nominal))
    for t_c in sorted({float(t) for t in table["temp_C"]}):
        d = replace(design, temperature=t_c + 273.15)
        cg = signal(d, None, backend)["cg_V_per_e"]
        read = noise(d, None, backend)["sigma_V"]
        m = d.fd_read(backend)
        for i in np.flatnonzero(table["temp_C"] == t_c):
            nominal[i] = read ** 2 + cg * max(float(v_nominal[i]), 0.0)
            ktc[i] = m["a_sf"] ** 2 * K_B * d.temperature / m["c_fd_F"]
    return {"nominal_V2": nominal, "ktc_V2": ktc}


def diagnose(design, table: dict, v_nominal: np.ndarray, backend: str = "batch") -> dict:
    """The noise column's verdict (module docstring): ``run`` False with ``why`` when it cannot be read."""
    from scipy.optimize import minimize_scalar

    from ..gap.diagnose import P_EXPLAINED
    from ..gap.pvalue import chi2_sf
    why = applies(design, table)
    if why is not None:
        return {"run": False, "why": why}
    p = parts(design, table, v_nominal, backend)
    s_meas = np.asarray(table["v_std_V"], float)
    n = np.asarray(table["n_avg"], float)
    def chi2(share: float) -> float:
        pred = np.sqrt(p["nominal_V2"] + share * p["ktc_V2"])
        return float(np.sum(((s_meas - pred) / np.maximum(pred / np.sqrt(2.0 * (n - 1.0)), 1e-9)) ** 2))
    rows = len(s_meas)
    chi0 = chi2(0.0)
    p0 = float(chi2_sf(chi0, rows))
    fit = minimize_scalar(chi2, bounds=(0.0, S_MAX), method="bounded", options={"xatol": 1e-4})
    share, chi_fit = float(fit.x), float(fit.fun)
    p_fit = float(chi2_sf(chi_fit, rows - 1))
    if p0 >= P_EXPLAINED:
        verdict = "the nominal read's noise explains the standard deviations (true CDS: FD's kT/C cancelled)"
    elif p_fit >= P_EXPLAINED:
        verdict = (f"ktc explains the standard deviations: {share:.2f} of FD's kT/C is left in the CDS output "
                   "(the reset sample and the signal sample are not of the same reset)")
    else:
        verdict = "neither the nominal read's noise nor FD's kT/C explains the standard deviations"
    return {"run": True, "effect": KTC, "what": KTC_WHAT, "rows": rows, "nominal_chi2": chi0,
            "nominal_p_value": p0, "share": share, "chi2": chi_fit, "p_value": p_fit,
            "at_bound": share >= S_MAX * 0.999, "explained": bool(p0 >= P_EXPLAINED or p_fit >= P_EXPLAINED),
            "best": "none" if p0 >= P_EXPLAINED else (KTC if p_fit >= P_EXPLAINED else "unexplained"),
            "nominal_std_V": np.sqrt(p["nominal_V2"]).tolist(), "ktc_rms_V": np.sqrt(p["ktc_V2"]).tolist(), "verdict": verdict}
