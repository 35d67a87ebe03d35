"""The SPICE side of the noise and gain: ``.noise`` decks + sampled-noise theory, SF gain.

An independent figure for the analytic chain of ``physics.noise``: the variances
come from ngspice's BSIM4 noise sources at the real operating points and from the
real device capacitances, not from the kit's C(V) model.

    var_col = A_sf^2 (var_FD,transfer + var_FD,reset) + var_read,NCDS
    var_read,NCDS = integral S_col(f) 2 (1 - cos 2 pi f dt) df

``dt`` is the time between the signal and the reset sample (NCDS), so the SF's
1/f noise is partly cancelled and its white noise doubled.
"""
from __future__ import annotations

import numpy as np

from ..circuits.noisebench import capacitor_deck, fd_sample_deck, read_deck
from ..circuits.testbench import timings
from ..errors import PixelkitError
from ..physics.noise import ncds_interval
from ..spice import simulate_many
from ..spice.batch import run_batch
from ..spice.engine import _prepare


def run_noise(net) -> dict:
    """Run a ``.noise`` deck: {"f": Hz, "psd": V^2/Hz, "total_V": integrated RMS}."""
    deck = _prepare(net, None)
    plots, lines, _ = run_batch(deck.text(), deck.model_links())
    spec = [p for p in plots if "onoise_spectrum" in p["data"]]
    tot = [p for p in plots if "v(onoise_total)" in p["data"]]
    if not spec or not tot:
        raise PixelkitError(f"noise run '{net.title}' failed: " + " | ".join(lines[-5:]))
    d = spec[0]["data"]
    return {"f": np.real(np.asarray(d["frequency"])), "psd": np.real(np.asarray(d["onoise_spectrum"])) ** 2,
            "psd_in": np.real(np.asarray(d["inoise_spectrum"])) ** 2,
            "total_V": float(np.real(np.asarray(tot[0]["data"]["v(onoise_total)"]))[0])}


def ktc_capacitor(design, r: float, c: float) -> float:
    """RMS noise (V) ngspice integrates on a bare capacitor ``c`` charged through ``r``."""
    return run_noise(capacitor_deck(design, r, c))["total_V"]


def sf_gain(design, v_fd: float | None = None, dv: float = 0.01, backend: str = "batch") -> float:
    """Small-signal gain dV_col/dV_FD of the SF + column load (RS on) at FD = ``v_fd`` (default the PD
    reset level): two operating points of the SF bench, ``v_fd`` -+ ``dv``."""
    from ..circuits.testbench import sf_bench
    v = design.pixel.v_pd_reset if v_fd is None else v_fd
    lo, hi = simulate_many([sf_bench(design, v - dv, title="sf_lo"), sf_bench(design, v + dv, title="sf_hi")],
                           backend=backend)
    return float((hi["v(col)"][0] - lo["v(col)"][0]) / (2 * dv))


def ncds_read(design, which: str, a_sf: float) -> float:
    """Variance (V^2) of the NCDS difference from the SF read chain (thermal + 1/f)."""
    r = run_noise(read_deck(design, design.pixel.v_pd_reset))
    dt = ncds_interval(design, which)
    w = 2.0 * (1.0 - np.cos(2 * np.pi * r["f"] * dt))
    return float(np.trapezoid(r["psd"] * w, r["f"]))


def pixel_noise(design, which: str, a_sf: float | None = None) -> dict:
    """SPICE read-noise figure of ``which`` subpixel at the column (V), by part."""
    a = sf_gain(design) if a_sf is None else a_sf
    sig = run_noise(fd_sample_deck(design, which, transfer=True))["total_V"] ** 2
    rst = run_noise(fd_sample_deck(design, which, transfer=False))["total_V"] ** 2
    read = ncds_read(design, which, a)
    total = a * a * (sig + rst) + read
    return {"a_sf": a, "fd_signal_V2": sig, "fd_reset_V2": rst, "read_ncds_V2": read,
            "pixel_V": float(np.sqrt(total))}


def output_cg(design, n_primary: float = 20000, n_secondary: float = 5000, backend: str = "batch") -> dict:
    """Output-referred CG (V/e-) from SPICE: a known photo-charge (I x the experiment's window)
    against a dark run, double-sampled at the column, per array."""
    from ..circuits.testbench import dual_pixel_bench
    from ..constants import Q
    from ..measure.pixel import double_sampled
    tw = design.experiment.t_window
    dark, step = simulate_many([dual_pixel_bench(design, 0.0, 0.0, title="cg_dark"),
                                dual_pixel_bench(design, n_primary * Q / tw, n_secondary * Q / tw, title="cg_step")],
                               backend=backend)
    tm = timings(design, tw)
    return {which: (double_sampled(step, col, tm[which]) - double_sampled(dark, col, tm[which])) / n
            for which, col, n in (("primary", "col_p", n_primary), ("secondary", "col_s0", n_secondary))}
