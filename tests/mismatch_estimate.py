"""Fixed-pattern noise of an array frame estimated without the Monte Carlo sampling.

The reference the Monte Carlo tests compare with: linear propagation of the model card's
mismatch through sensitivities measured on nominal decks. Each deck is the frame's own
circuit (``array_bench``, 2 rows x 1 dual-pixel column, dark, no statistics) with one
device kind moved deterministically:

- its threshold by ``DV`` = 20 mV: a DC source in series with its gate (V_GS + dV is
  V_T - dV for the channel and its current; the gate's own swing is unchanged);
- its current factor by ``DK`` = 2 %: W x 1.02 (for the SF, RS, load and bias devices,
  whose own channel charge does not act between the two samples; the W-scaled junction and
  overlap capacitances are a small error of this proxy). The switches EC, TG, RST settle
  fully, so their current factor is left out. The column precharge switch of a precharged read
  (``pre_on`` / ``pre_off``) is left out altogether: its V_T moved +-20 mV changes the dark signal
  of the reference design by < 0.001 mV (the follower re-settles the line after it opens), and a
  Monte Carlo frame with only its statistics on moves the pedestal 0.000 mV (docs/validation.md).

The decks run at reltol 1e-6: at the kit's 1e-5 two decks with different step sequences
scatter by ~0.1 mV, as much as a 10 mV threshold moves the signal (it doubled the estimate).
A pixel device moves every pixel's signal (the subcircuit is shared), a column device
(load, bias generator) every column's: the slope of the dark signal is the sensitivity of
one pixel to its own device. The model card's sigmas, written here from
``sm141064.ngspice`` (section ``fets_mm``, nfet_03v3) as printed: one device draws
``0.7071 par 1e-6 / sqrt((L - par_l)(W - par_w))`` with par_vth = 7.148e-3,
par_k = 7.008e-3, par_l = 0.15 um, par_w = -0.1 um (micrometres inside the root).

    sigma_pix^2 = sum over EC, TG, RST, SF, RS of (dS/dV_T sigma_VT)^2 + SF, RS (dS/dk sigma_k)^2
    sigma_col^2 = the same over the column's load and its bias generator
    DSNU^2 ~= sigma_pix^2 + sigma_col^2,   column FPN^2 ~= sigma_col^2 + sigma_pix^2 / rows

and PRNU the same sum over the response (flat - dark) at the Monte Carlo chip's flat field
(50 % of the primary's full scale, ``chip.scene``), over its nominal mean, plus what is not
mismatch: the rows of a global-shutter frame wait one row time more each on FD, where
1/gse of the PD's light adds to the signal (primary: ~1 mV per row at this field): the
nominal decks' step from row 0 to row 1, as a ramp over the frame's rows (sigma = step
sqrt((rows^2 - 1) / 12)), adds in quadrature.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from scipy.stats import chi2

from pixelkit.chip.scene import default_map, photocurrents
from pixelkit.circuits.array import array_bench, frame_timings
from pixelkit.spice import simulate_many
from pixelkit.spice.netlist import Element

PAR_VTH, PAR_K, PAR_L, PAR_W = 7.148e-3, 7.008e-3, 0.15, -0.1
DV, DK = 0.02, 0.02
ROWS = 2
PIXEL = ("ec", "tg", "rst", "sf", "rs")
BETA = ("sf", "rs")


def sigma(w: float, l: float, par: float) -> float:
    """One device's sigma (V for par_vth, relative for par_k); w, l in metres."""
    return 0.7071 * par / math.sqrt((l * 1e6 - PAR_L) * (w * 1e6 - PAR_W))


def _edit(el: Element, kind: str) -> tuple:
    if kind == "k":
        p = dict(el.params)
        p["w"] = p["w"] * (1 + DK)
        return (replace(el, params=tuple(p.items())),)
    nodes = list(el.nodes)
    gate = nodes[1]
    nodes[1] = f"{gate}_dvt_{el.name}"
    return (replace(el, nodes=tuple(nodes)), Element(f"Vdvt_{el.name}", (nodes[1], gate), DV))


def _moved(net, device: str, kind: str):
    """``net`` with ``device`` (a pixel device name, or 'ld' / 'bias' for the column's) moved."""
    if device in PIXEL:
        subs = []
        for s in net.subckts:
            if s.name.startswith("pix5t_"):
                els = []
                for e in s.elements:
                    els += _edit(e, kind) if e.name.lower() == f"x{device}" else (e,)
                s = replace(s, elements=tuple(els))
            subs.append(s)
        return replace(net, subckts=tuple(subs), title=f"{net.title}_{device}_{kind}")
    els = []
    for e in net.elements:
        els += _edit(e, kind) if e.name.lower().startswith(f"x{device}_") else (e,)
    return replace(net, elements=tuple(els), title=f"{net.title}_{device}_{kind}")


def _signals(res, tm) -> dict:
    out = {}
    for kind, node in (("primary", "col_p_0"), ("secondary", "col_s_0")):
        t = tm[kind]
        out[kind] = float(np.mean([res.at(node, t.t_reset_level(r)) - res.at(node, t.t_signal(r))
                                   for r in range(ROWS)]))
    return out


def estimate(design, rows: int, jobs: int = 2) -> dict:
    """{kind: {sigma_pix_V, sigma_col_V, dsnu_V, column_fpn_V, nominal_dark_V, prnu_pct, parts_V}}
    for a frame of ``rows``."""
    dev = design.pixel.devices
    t_exp = design.experiment.t_window
    tm = frame_timings(design, t_exp, ROWS)
    n = design.secondary_per_pixel
    m, unit = default_map(ROWS, n, "uniform")
    ph = photocurrents(design, ROWS, 1, m, unit)
    step = min(t.t_row for t in tm.values()) / 2
    dark = array_bench(design, np.zeros((ROWS, 1)), np.zeros((ROWS, n)), t_exp=t_exp, max_step=step,
                       title="fpn_estimate")
    flat = array_bench(design, ph.iph_p, ph.iph_s, t_exp=t_exp, max_step=step, title="fpn_estimate_flat")
    moves = [(d, "vt") for d in (*PIXEL, "ld", "bias")] + [(d, "k") for d in (*BETA, "ld", "bias")]
    decks = [net for base in (dark, flat) for net in [base] + [_moved(base, d, k) for d, k in moves]]
    runs = simulate_many(decks, jobs=jobs, options=(("reltol", 1e-6),))
    sig = [_signals(r, tm) for r in runs]
    dark_sig, flat_sig = sig[:len(moves) + 1], sig[len(moves) + 1:]
    # the storage adds a signal linear in the wait, one row time more per row: from the nominal
    # decks' two rows, the spread of that ramp over the frame's rows
    ramp = {}
    for kind, node in (("primary", "col_p_0"), ("secondary", "col_s_0")):
        t = tm[kind]
        by_row = [(runs[len(moves) + 1].at(node, t.t_reset_level(r)) - runs[len(moves) + 1].at(node, t.t_signal(r)))
                  - (runs[0].at(node, t.t_reset_level(r)) - runs[0].at(node, t.t_signal(r))) for r in range(ROWS)]
        ramp[kind] = abs(float(by_row[1] - by_row[0])) * math.sqrt((rows * rows - 1) / 12.0)
    geo = {"ec": (dev.ec_w, dev.ec_l), "tg": (dev.tg_w, dev.tg_l), "rst": (dev.rst_w, dev.rst_l),
           "sf": (dev.sf_w, dev.sf_l), "rs": (dev.rs_w, dev.rs_l), "ld": (dev.load_w, dev.load_l),
           "bias": (dev.load_w, dev.load_l)}
    out = {}
    for kind in ("primary", "secondary"):
        parts, resp = {}, {}
        for j, (d, k) in enumerate(moves, 1):
            step_ = DV if k == "vt" else DK
            sd = sigma(*geo[d], PAR_VTH if k == "vt" else PAR_K)
            parts[f"{d}_{k}"] = (dark_sig[j][kind] - dark_sig[0][kind]) / step_ * sd
            resp[f"{d}_{k}"] = ((flat_sig[j][kind] - dark_sig[j][kind]) - (flat_sig[0][kind] - dark_sig[0][kind])) \
                / step_ * sd
        pix = math.sqrt(sum(v * v for key, v in parts.items() if key.split("_")[0] in PIXEL))
        col = math.sqrt(sum(v * v for key, v in parts.items() if key.split("_")[0] in ("ld", "bias")))
        mean_resp = flat_sig[0][kind] - dark_sig[0][kind]
        r_pix = math.sqrt(sum(v * v for key, v in resp.items() if key.split("_")[0] in PIXEL))
        r_col = math.sqrt(sum(v * v for key, v in resp.items() if key.split("_")[0] in ("ld", "bias")))
        out[kind] = {"sigma_pix_V": pix, "sigma_col_V": col, "dsnu_V": math.hypot(pix, col),
                     "column_fpn_V": math.sqrt(col * col + pix * pix / rows), "nominal_dark_V": dark_sig[0][kind],
                     "prnu_pix_pct": 100 * math.hypot(r_pix, ramp[kind]) / mean_resp,
                     "prnu_col_pct": 100 * r_col / mean_resp, "prnu_rows_pct": 100 * ramp[kind] / mean_resp,
                     "prnu_pct": 100 * math.sqrt(r_pix ** 2 + r_col ** 2 + ramp[kind] ** 2) / mean_resp,
                     "parts_V": parts}
    return out


def sample_band(dof: int, p: float = 1e-3, model: float = 0.1) -> tuple[float, float]:
    """Bounds of (sample sigma) / (true sigma) with ``dof`` degrees of freedom at two-sided
    probability ``p``, widened by the estimate's own ``model`` error."""
    lo, hi = (math.sqrt(chi2.ppf(q, dof) / dof) for q in (p / 2, 1 - p / 2))
    return lo / (1 + model), hi * (1 + model)


def effective_dof(pix: float, col: float, n: int, cols: int) -> int:
    """Satterthwaite's degrees of freedom of a sample sigma over ``n`` pixels in ``cols`` columns
    whose spread has a pixel part ``pix`` and a column part ``col``."""
    p2, c2 = pix * pix, col * col
    return max(1, round((p2 + c2) ** 2 / (p2 * p2 / (n - cols) + c2 * c2 / (cols - 1))))
