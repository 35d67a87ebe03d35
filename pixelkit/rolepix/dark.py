"""Dark current at the CDS output: one dark pixel, a frame of the shortest exposure and a frame of
the design's integration time; the difference of their CDS outputs over the conversion gain and the
difference of the exposures. At 27 degC a pinned photodiode collects a few tens of electrons per
second, a fraction of an electron in 10 ms: the deck runs with reltol 1e-7 and vntol 1 nV (the
defaults, 1e-5 and 1 uV, leave errors of a few uV, a tenth of an electron) and takes large steps
through the exposure (the read's edges are breakpoints)."""
from __future__ import annotations

from dataclasses import replace

from ..spice.netlist import Tran
from .run import run

#: tolerances of the dark deck
OPTIONS = (("reltol", 1e-7), ("vntol", 1e-9))


def dark(design, draw=None, backend: str = "batch") -> dict:
    from ..circuits.cds import cds_bench, timing_of
    from ..measure.cds import cds
    from .signal import flush_exposure
    t0, t_int = flush_exposure(design), design.array.t_int
    t_int = max(t_int, 2 * t0)
    ex = [t0, t0, t_int]
    net = cds_bench(design, design.cell(), ex, [[0.0, 0.0, 0.0]], title="role_dark")
    tm = timing_of(design)
    net = replace(net, options=(*net.options, *OPTIONS), analysis=Tran(1e-9, net.analysis.stop, 0.0, tm.t_row / 4, uic=True))
    (r,) = run([net], design, draw, backend)
    st = net.meta["frames"]["starts"]
    short, long_ = (cds(r, tm, ex, st, 0, f) for f in (1, 2))
    return {"dark_V": long_ - short, "dt_s": t_int - t0, "short_V": short}
