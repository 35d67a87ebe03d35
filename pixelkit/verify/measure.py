"""Measurements of the sign-off figures at one condition (and one Monte Carlo draw).

A *group* is a set of decks run together; ``run_group`` returns its raw measurements
(plain floats, SI) and ``figures`` turns the groups' raw numbers into the figures of
``verify.figures``. Only the groups the specs need are run.

- ``pixel``: the dual-pixel bench (``circuits.testbench.dual_pixel_bench``) over the
  experiment's window: dark, a small signal (~3 % of the PD range), saturation (the PD
  driven to 0.5 V, as the experiment's sweep top), then the primary bracketing
  mid-scale at two currents predicted from the first three, each with the secondaries
  at the *equivalent* current (the method of [Thesis2019]: I_s = I_p (A_s / A_p)
  (t_s / t_p), same window).
- ``gse``: the same bench with and without storage, with and without light.
- ``storage``: a dark exposure, then the storage node lit over the last row's wait by a bright
  source's FD current (photocurrent / GSE).
- ``lag``: dark frames that follow the saturated and the dark frame.
- ``noise``: the SF gain from two operating points of the read chain, then the read-noise
  chain of ``physics.noise`` at the condition's temperature.
- ``dark``: the PD with its EC and TG, dark, over each subpixel's ``t_int``
  (``circuits.testbench.dark_bench``).
- ``afe``: the SC AFE bench at three input steps.
- ``settling``: a 2-row dual column with its AFE, each row against the same read with long
  S1 and S2 from the same column state (``chip.settling``, as ``pixelkit array``).
- ``power``: ``verify.power``.
"""
from __future__ import annotations

import contextlib
import contextvars
from dataclasses import replace

import numpy as np

from ..constants import Q
from . import mismatch
from .copies import one_column

#: The small-signal point: this fraction of the current that takes the PD to 0.5 V.
SMALL = 1.0 / 40
#: Brackets of mid-scale around the linear prediction (the column compresses ~5 % there).
BRACKET = (0.98, 1.12)
#: Storage of the GSE decks, in exposure windows.
STORE = 4


#: While ``recording()`` is active: the results of every deck the measurements run, by deck title,
#: and every reading they take (the waveform view of a spec, ``verify.waves``).
_RECORD: contextvars.ContextVar = contextvars.ContextVar("pixelkit_verify_record", default=None)


@contextlib.contextmanager
def recording():
    """Collect ``{"results": {title: Result}, "marks": [{deck, node, t, v, what}]}`` of the
    measurements run inside (same decks, same readings: the sim cache serves them again)."""
    rec = {"results": {}, "marks": []}
    token = _RECORD.set(rec)
    try:
        yield rec
    finally:
        _RECORD.reset(token)


#: While ``asking()`` is active: the figure names a task measures (``verify.run``: its specs'); a group
#: leaves out the decks that only feed figures outside it. None: every figure of the group.
_ASKED: contextvars.ContextVar = contextvars.ContextVar("pixelkit_verify_asked", default=None)


@contextlib.contextmanager
def asking(names):
    """Measure only what the figures ``names`` need (None: everything) inside."""
    token = _ASKED.set(None if names is None else frozenset(names))
    try:
        yield
    finally:
        _ASKED.reset(token)


def _asked(name: str) -> bool:
    names = _ASKED.get()
    return names is None or name in names


def _mark(r, node: str, t: float, what: str) -> None:
    rec = _RECORD.get()
    if rec is not None:
        rec["marks"].append({"deck": r.meta.get("title"), "node": node, "t": float(t),
                             "v": float(r.at(node, t)), "what": what})


def record(results) -> None:
    """Keep ``results`` (by deck title) while ``recording()`` is active."""
    rec = _RECORD.get()
    if rec is not None:
        rec["results"].update({r.meta.get("title"): r for r in results})


def _run(nets, design, draw, backend):
    from ..spice import simulate_many
    out = simulate_many([mismatch.apply(n, design, draw) for n in nets], backend=backend, jobs=1)
    record(out)
    return out


def _i_max(design, kind):
    from ..experiments.thesis import _i_max as i_max
    return i_max(design, kind)


def _ratio(design) -> float:
    """Secondary / primary collected charge under the same light over the designed t_int."""
    p, s = design.primary, design.secondary
    return (s.photoactive_area / p.photoactive_area) * (s.t_int / p.t_int)


def _pd_drop(r, node, t):
    t0, t1 = t.t_start + t.edge + 50e-9, t.t_tx - t.t_tg
    _mark(r, node, t0, "PD after reset")
    _mark(r, node, t1, "PD before transfer")
    return float(r.at(node, t0) - r.at(node, t1)), t1 - t0


def _end_state(r) -> tuple:
    """Initial conditions of a frame that follows the one ``r`` simulated: every pixel node and
    column line where that frame ended (a frame after a saturated one starts from its state)."""
    out = []
    for key in r.names():
        node = key[2:-1]
        if key.startswith("v(") and (node.startswith("col_") or node.count(".") == 2):
            out.append((node, float(r.vectors[key][-1])))
    return tuple(out)


class _Bench:
    """The dual-pixel bench of a design over the experiment's window, and its readings."""

    def __init__(self, design):
        from ..circuits.testbench import timings
        self.design, self.n = design, design.secondary_per_pixel
        self.tw = design.experiment.t_window
        self.tm = timings(design, self.tw)
        self.i_max = (_i_max(design, "primary"), _i_max(design, "secondary"))

    def cols(self) -> tuple:
        return ("col_p", *(f"col_s{k}" for k in range(self.n)))

    def state(self) -> tuple:
        """Every pixel node a following frame starts from (``_end_state``), and the columns."""
        subs = ("xp", *(f"xs{k}" for k in range(self.n)))
        return (*self.cols(), *(f"x1.{s}.{node}" for s in subs for node in ("pd", "fd", "sfo")))

    def net(self, ip, is_, title, saves=None, **kw):
        """The bench saving only ``saves`` (default: the column lines): fewer vectors to write,
        cache and read back."""
        from ..circuits.testbench import dual_pixel_bench
        net = dual_pixel_bench(self.design, ip, is_, title=title, **kw)
        return replace(net, saves=tuple(saves or self.cols()))

    def sig(self, r, tm=None):
        """(primary, mean of the secondaries) double-sampled column signals."""
        from ..measure.pixel import double_sampled
        tm = tm or self.tm
        if _RECORD.get() is not None:
            for col, kind in (("col_p", "primary"), *((f"col_s{k}", "secondary") for k in range(self.n))):
                _mark(r, col, tm[kind].t_reset_level(0), "reset level")
                _mark(r, col, tm[kind].t_signal(0), "signal level")
        return (double_sampled(r, "col_p", tm["primary"]),
                float(np.mean([double_sampled(r, f"col_s{k}", tm["secondary"]) for k in range(self.n)])))

    def dark(self):
        return self.net(0.0, 0.0, "vfy_dark", saves=self.state())

    def sat(self):
        return self.net(*self.i_max, "vfy_sat", saves=self.state())

    def small(self):
        i = self.i_max
        return self.net(SMALL * i[0], SMALL * i[1], "vfy_small", saves=(*self.cols(), "x1.xp.pd", "x1.xs0.pd"))


def pixel(design, draw=None, backend="batch") -> dict:
    b = _Bench(design)
    tw, tm = b.tw, b.tm
    dark, small, sat = _run([b.dark(), b.small(), b.sat()], design, draw, backend)
    (d_p, d_s), (s_p, s_s), (t_p, t_s) = b.sig(dark), b.sig(small), b.sig(sat)
    swing_p, swing_s = t_p - d_p, t_s - d_s
    i_small_p, i_small_s = SMALL * b.i_max[0], SMALL * b.i_max[1]
    out = {"dark_V": [d_p, d_s], "swing_V": [swing_p, swing_s],
           "cg_out_V_per_e": [(s_p - d_p) / (i_small_p * tw / Q), (s_s - d_s) / (i_small_s * tw / Q)]}
    cg_pd = []
    for name, i, kind in (("x1.xp.pd", i_small_p, "primary"), ("x1.xs0.pd", i_small_s, "secondary")):
        drop, dt = _pd_drop(small, name, tm[kind])
        drop0, _ = _pd_drop(dark, name, tm[kind])
        cg_pd.append((drop - drop0) / (i * dt / Q))
    out["cg_pd_V_per_e"] = cg_pd
    # mid-scale bracket from the small signal's slope, the secondaries at the equivalent current
    mid = design.experiment.mid_fraction
    i_lin = i_small_p * mid * swing_p / (s_p - d_p)
    currents = [f * i_lin for f in BRACKET]
    r_i = _ratio(design)
    lo, hi = _run([b.net(currents[0], currents[0] * r_i, "vfy_mid_lo"),
                   b.net(currents[1], currents[1] * r_i, "vfy_mid_hi")], design, draw, backend)
    (lo_p, lo_s), (hi_p, hi_s) = b.sig(lo), b.sig(hi)
    f_p = np.array([lo_p - d_p, hi_p - d_p]) / swing_p
    f_s = np.array([lo_s - d_s, hi_s - d_s]) / swing_s
    out["mid_bracket"] = {"currents_A": currents, "primary_frac": f_p.tolist(), "secondary_frac": f_s.tolist()}
    k = (f_s[1] - f_s[0]) / (f_p[1] - f_p[0])   # linear between (or beyond) the two points
    out["criterion"] = float(f_s[0] + k * (mid - f_p[0]))
    out["criterion_extrapolated"] = not f_p[0] <= mid <= f_p[1]
    return out


def gse(design, draw=None, backend="batch") -> dict:
    """Storage: with anti-blooming (EC holds the PD in reset: it must not overflow onto FD while
    FD stores) the same decks with and without STORE windows of storage, with and without light
    (each kind at its mid-scale current from the PD model, so the storage signal is mV, far above
    the solver's noise). GSE = exposure signal over storage signal per window."""
    from ..circuits.testbench import timings
    from ..chip.scene import default_stimulus
    b = _Bench(design)
    st = default_stimulus(design, b.tw)
    i = (st["iph_p"], 10 * st["iph_s"])   # both at ~half of their PD range
    t_no, t_st = timings(design, b.tw, ec_hold=True), timings(design, b.tw, t_store=STORE * b.tw, ec_hold=True)
    runs = _run([b.net(*i, "vfy_gse_l0", tm=t_no), b.net(*i, "vfy_gse_l1", tm=t_st),
                 b.net(0.0, 0.0, "vfy_gse_d0", tm=t_no), b.net(0.0, 0.0, "vfy_gse_d1", tm=t_st)], design, draw, backend)
    (l0, l0s), (l1, l1s), (e0, e0s), (e1, e1s) = (b.sig(r, t) for r, t in zip(runs, (t_no, t_st, t_no, t_st)))
    expo = [l0 - e0, l0s - e0s]
    store = [((l1 - e1) - (l0 - e0)) / STORE, ((l1s - e1s) - (l0s - e0s)) / STORE]
    return {"gse": [e / x if x > 0 else float("inf") for e, x in zip(expo, store)], "exposure_signal_V": expo,
            "storage_signal_V": store}


def storage(design, draw=None, backend="batch") -> dict:
    """The storage node's light over a frame's readout: per array, a dark exposure, then FD holds for the
    last row's wait ((rows - 1) row times after the transfer, EC holding the PD) while a source
    ``light.source_factor`` x the background lights the pixel: FD collects the photodiode's photocurrent
    over its GSE (``physics.fd.gse``), put on FD as a current for the hold. The signal it adds is the
    double-sampled signal against the same dark deck without it."""
    from ..circuits.testbench import timings
    from ..gap.circuit_edits import EDGE, add_to_subckt, pulse
    from ..optimize.sizing import light
    from ..physics.fd import gse
    from ..spice.netlist import Element
    b = _Bench(design)
    j_bg = light(design).j_bg
    out = {"signal_V": [], "fd_current_A": [], "hold_s": []}
    for i, kind in enumerate(("primary", "secondary")):
        if not _asked(f"storage_light_{kind}"):   # its two decks feed that figure only
            out["signal_V"].append(float("nan"))
            out["fd_current_A"].append(float("nan"))
            out["hold_s"].append(float("nan"))
            continue
        sub = getattr(design, kind)
        tm = timings(design, b.tw, t_store=(sub.rows - 1) / sub.f_read, ec_hold=True)
        t0, t1 = tm[kind].t_tx + 2 * EDGE, tm[kind].t_read
        i_fd = design.light.source_factor * j_bg * sub.photoactive_area / gse(design, kind)
        dark = b.net(0.0, 0.0, f"vfy_sto_dark_{kind}", tm=tm)
        lit = add_to_subckt(b.net(0.0, 0.0, f"vfy_sto_lit_{kind}", tm=tm), f"pix5t_{kind}",
                            Element("Isto", ("fd", "0"), pulse(t0, t1, i_fd)))
        r_dark, r_lit = _run([dark, lit], design, draw, backend)
        out["signal_V"].append(b.sig(r_lit, tm)[i] - b.sig(r_dark, tm)[i])
        out["fd_current_A"].append(i_fd)
        out["hold_s"].append(t1 - t0 - EDGE)
    return out


def lag(design, draw=None, backend="batch") -> dict:
    """A dark frame after a saturated one against a dark frame after a dark one, each starting
    from the state the previous frame ended in (``_end_state``)."""
    b = _Bench(design)
    dark, sat = _run([b.dark(), b.sat()], design, draw, backend)
    after_dark, after_sat = _run([replace(b.net(0.0, 0.0, "vfy_lag_dark"), ic=_end_state(dark)),
                                  replace(b.net(0.0, 0.0, "vfy_lag_sat"), ic=_end_state(sat))], design, draw, backend)
    (a_p, a_s), (s_p, s_s), (d_p, d_s), (t_p, t_s) = b.sig(after_dark), b.sig(after_sat), b.sig(dark), b.sig(sat)
    return {"lag_V": [s_p - a_p, s_s - a_s], "swing_V": [t_p - d_p, t_s - d_s]}


def noise(design, draw=None, backend="batch") -> dict:
    from ..circuits.testbench import sf_bench
    from ..physics.noise import chain
    from ..techfit.ekv import models_for
    v, dv = design.pixel.v_fd_reset, 0.05
    lo, hi = _run([sf_bench(design, v - dv, title="vfy_sf_lo"), sf_bench(design, v + dv, title="vfy_sf_hi")],
                  design, draw, backend)
    a_sf = float((hi["v(col)"][0] - lo["v(col)"][0]) / (2 * dv))
    out = {"a_sf": a_sf}
    sf_models = models_for(design)
    for kind in ("primary", "secondary"):
        c = chain(design, kind, a_sf, sf_models)
        out[kind] = {"read_e": c["afe_e"], "ktc_e": c["electrons"]["fd_reset_ncds"], "pixel_e": c["pixel_e"]}
    return out


def dark(design, draw=None, backend="batch") -> dict:
    from ..circuits.testbench import dark_bench
    nets = [replace(dark_bench(design, k, getattr(design, k).t_int, title=f"vfy_dark_{k[0]}"), saves=("pd",))
            for k in ("primary", "secondary")]
    out = {}
    for k, r in zip(("primary", "secondary"), _run(nets, design, draw, backend)):
        t0 = getattr(design, k).timing.t_reset + 50e-9  # dark_bench: EC resets for t_reset
        _mark(r, "pd", t0, "after reset")
        _mark(r, "pd", r.time[-1], "after t_int")
        out[k] = float(r.at("pd", t0) - r["v(pd)"][-1])
    return out


def afe(design, draw=None, backend="batch") -> dict:
    from ..circuits.testbench import afe_bench
    from ..physics.timing import GsTiming
    from ..measure.afe import afe_output
    a = design.afe
    v_rst, dv = 1.9, np.array([0.1, 0.35, 0.6])
    net = replace(afe_bench(design, [(v_rst - x, v_rst) for x in dv], title="vfy_afe"), saves=("out",))
    (r,) = _run([net], design, draw, backend)
    t = GsTiming(t_exp=0.0, t_row=1 / a.f_clk, rows=len(dv), t_reset=0.0, t_tg=0.0, t_gap=0.0, t_pre=0.0)
    out = np.array([afe_output(r, t, k) for k in range(len(dv))])
    for k in range(len(dv)):
        _mark(r, "out", t.t_reset_level(k), f"output, step {k + 1}")
    slope = float(np.polyfit(dv, out, 1)[0])
    return {"gain": -slope, "ideal": a.c11 / a.c13}


def settling(design, draw=None, backend="batch") -> dict:
    """Worst |settling error| (V) of each array over a 2-row dual column with its AFE at the
    default stimulus: each row's double-sampled signal against the same read with long S1 and
    S2 from the same column state (``chip.settling``). Nominal devices: a Monte Carlo draw
    does not enter (the figure's ``mc`` is false).

    Both reads run at ``chip.frame.CONVERGED`` tolerances (reltol 1e-6, abstol 1e-12): at the engine's
    default reltol 1e-5 the difference of the two reads carries the integration error of each, 0.1 -
    0.6 mV on the reference's revision B and the GF180 port (0.568 mV at tt -20 degC +10 % on the
    GF180 port's revision B, 0.016 mV converged), as large as the 0.5 mV limit: the figure would
    measure the solver, not the read. Converged costs ~30 % more on these decks.

    The secondary chain simulates one of the N identical secondary columns (``one_column``): the
    worst of N copies is that of one."""
    from ..chip.frame import CONVERGED, simulate_frame
    from ..chip.scene import default_stimulus
    design = one_column(design) or design
    n = design.secondary_per_pixel
    stim = default_stimulus(design, design.experiment.t_window)
    ip, is_ = np.full((2, 1), stim["iph_p"]), np.full((2, n), stim["iph_s"])
    f = simulate_frame(design, ip, is_, with_afe=True, split="columns", settling=True, backend=backend, jobs=1,
                       options=CONVERGED)
    return {k: float(np.nanmax(np.abs(f.settling[k]))) if np.isfinite(f.settling[k]).any() else float("nan")
            for k in ("primary", "secondary")}


def power(design, draw=None, backend="batch") -> dict:
    from .power import measure
    return measure(design, draw, backend)


GROUPS = {"pixel": pixel, "gse": gse, "storage": storage, "lag": lag, "noise": noise, "dark": dark, "afe": afe, "settling": settling, "power": power}


def run_group(group: str, design, draw=None, backend: str = "batch") -> dict:
    return GROUPS[group](design, draw, backend)


def groups_for(figure_names) -> list[str]:
    from .figures import FIGURES, groups_of
    return groups_of(figure_names, FIGURES)


def figures(raw: dict) -> dict:
    """Every figure the raw measurements of the groups in ``raw`` give (SI)."""
    out = {}
    px, nz = raw.get("pixel"), raw.get("noise")
    for i, kind in enumerate(("primary", "secondary")):
        if px:
            cg = px["cg_out_V_per_e"][i]
            out[f"conversion_gain_{kind}"] = cg / Q
            out[f"pd_conversion_gain_{kind}"] = px["cg_pd_V_per_e"][i] / Q
            out[f"swing_{kind}"] = px["swing_V"][i]
            out[f"full_well_{kind}"] = px["swing_V"][i] / cg * Q
        if nz:
            out[f"read_noise_{kind}"] = nz[kind]["read_e"] * Q
            out[f"ktc_noise_{kind}"] = nz[kind]["ktc_e"] * Q
        if px and nz:
            out[f"dynamic_range_{kind}"] = (px["swing_V"][i] / px["cg_out_V_per_e"][i]) / nz[kind]["read_e"]
        if raw.get("gse"):
            out[f"gse_{kind}"] = raw["gse"]["gse"][i]
        if raw.get("storage") and px:
            out[f"storage_light_{kind}"] = raw["storage"]["signal_V"][i] / px["swing_V"][i]
        if raw.get("lag"):
            out[f"image_lag_{kind}"] = abs(raw["lag"]["lag_V"][i]) / raw["lag"]["swing_V"][i]
        if raw.get("dark"):
            out[f"pd_dark_drop_{kind}"] = raw["dark"][kind]
        if raw.get("settling"):
            out[f"settling_{kind}"] = raw["settling"][kind]
    if px:
        out["criterion_secondary"] = px["criterion"]
    if raw.get("afe"):
        out["afe_gain_error"] = abs(raw["afe"]["gain"] / raw["afe"]["ideal"] - 1.0)
    if raw.get("power"):
        for k in ("pixel", "column", "chip"):
            out[f"power_{k}"] = raw["power"][f"{k}_W"]
    return out


def mark(r, node: str, t: float, what: str) -> None:
    """A reading a measurement took (kept while ``recording()`` is active): the waveform view's marks."""
    _mark(r, node, t, what)
