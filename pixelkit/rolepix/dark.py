"""Dark current at the CDS output: one dark pixel, a frame of the shortest exposure and a frame of
the design's integration time; the difference of their CDS outputs over the conversion gain and the
difference of the exposures. At 27 degC a pinned photodiode collects a few tens of electrons per
second, a fraction of an electron in 10 ms: the deck runs with reltol 1e-7 and vntol 1 nV (the
defaults, 1e-5 and 1 uV, leave errors of a few uV, a tenth of an electron) and takes large steps
through the exposure (the read's edges are breakpoints).

Even so each held level carries a time-step error of about a uV (docs/pixel4t.md, "The post-layout dark
figure": the 4T's post-layout view read 8.7 - 18.6 e-/s against 14.6 e-/s as the deck's step changed), so a
dark signal below ``MIN_SIGNAL_V`` is read again over a longer exposure scaled to bring it to twice that (up
to ``RE_READS`` times, at most ``MAX_EXPOSURE``): the dark current is a rate, and the PPD far below its full well collects it linearly."""
from __future__ import annotations

from dataclasses import replace

from ..spice.netlist import Tran
from .run import run

#: tolerances of the dark deck
OPTIONS = (("reltol", 1e-7), ("vntol", 1e-9))
#: a dark signal read again when below this (V; a held level's time-step error is ~1 uV, in some decks up to
#: ~10 uV), over an exposure scaled to bring it to twice this, at most ``RE_READS`` times; the longest exposure (s)
MIN_SIGNAL_V = 100e-6
RE_READS = 3
MAX_EXPOSURE = 0.5


def _frames(design, t_int: float, draw, backend) -> dict:
    from ..circuits.cds import cds_bench, timing_of
    from ..measure.cds import cds
    from .signal import flush_exposure
    t0 = flush_exposure(design)
    t_int = max(t_int, 2 * t0)
    ex = [t0, t0, t_int]
    net = cds_bench(design, design.cell(), ex, [[0.0, 0.0, 0.0]], title="role_dark")
    tm = timing_of(design)
    net = replace(net, options=(*net.options, *OPTIONS), analysis=Tran(1e-9, net.analysis.stop, 0.0, tm.t_row / 4, uic=True))
    (r,) = run([net], design, draw, backend)
    st = net.meta["frames"]["starts"]
    short, long_ = (cds(r, tm, ex, st, 0, f) for f in (1, 2))
    return {"dark_V": long_ - short, "dt_s": t_int - t0, "short_V": short, "exposure_s": t_int}


def dark(design, draw=None, backend: str = "batch") -> dict:
    r = _frames(design, design.array.t_int, draw, backend)
    first = r
    for _ in range(RE_READS):
        if abs(r["dark_V"]) >= MIN_SIGNAL_V or r["exposure_s"] >= MAX_EXPOSURE:
            break
        longer = min(MAX_EXPOSURE, r["exposure_s"] * max(2.0, 2 * MIN_SIGNAL_V / max(abs(r["dark_V"]), 1e-6)))
        r = _frames(design, longer, draw, backend)
    if r is not first:
        r = {**r, "first_exposure_s": first["exposure_s"], "first_dark_V": first["dark_V"]}
    return r
