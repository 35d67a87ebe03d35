"""Read noise of the true-CDS read: ngspice ``.noise`` of the read chain and the CDS weighting.

The read operating point: RS on, RST and TG off, the light off, FD at the level it has when SHR
samples (read from the lag deck's dark pixel: the cell's ``fd`` probe), the SHR switch closed onto
its capacitor. ``.noise`` (BSIM4's channel thermal and flicker noise of every device: the pixel's,
the column load and its mirror, the S/H switch) gives the power spectral density S(f) at the S/H
node. The reset and the signal sample are taken ``dt`` apart (``CdsTiming.cds_interval``): their
difference has the variance

    sigma^2 = integral S(f) 2 (1 - cos 2 pi f dt) df

(noise correlated between the two samples - the follower's 1/f, FD's reset noise - cancels, white
noise counts twice; each S/H switch's own kT/C is white far beyond 1 / dt and counts once per
sample). FD's reset (kT/C) noise is the RST channel's noise filtered by FD: with RST off its corner
lies below 1 Hz, so the weighting removes it, as true CDS does. Input-referred: sigma / CG.
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError
from ..spice.netlist import Element
from .run import apply_draw

F_RANGE = (1.0, 1e10)
POINTS = 20


def read_point(design, backend: str = "batch") -> dict:
    """FD's and the column's level when SHR samples, from the lag deck's dark pixel (a cache hit after
    ``signal``)."""
    from ..circuits.cds import timing_of
    from .signal import lag_run
    cell = design.cell()
    fd = cell.probe("fd")
    if not fd:
        raise ConfigError(cell.source, "netlist.probes.fd", None, "the FD node (probe role 'fd'): the read "
                          "noise's operating point is FD's level at the reset sample")
    _out, r, net, _lad = lag_run(design, None, backend)
    tm, st = timing_of(design), net.meta["frames"]["starts"]
    t = st[1] + tm.frame(design.experiment.t_window).t_read + tm.shr[1] - tm.edge
    return {"v_fd": float(r.at(f"v(x0.{fd})", t)), "v_col": float(r.at("v(col0)", t))}


def deck(design, v_fd: float):
    """The read chain at its operating point, ``.noise`` at the SHR capacitor (module docstring)."""
    from ..circuits.cds import bias, deck as cds_deck, instance, supplies
    from ..circuits.devices import mosfet
    from ..circuits.noisebench import NOISE_OPTIONS, Noise
    cell, c, t = design.cell(), design.column, design.tech
    vdd = t.supply
    sup = [e for e in supplies(design, cell) if e.name != "Vrstd"]
    if cell.port("vrst"):
        sup.append(Element("Vrstd", ("vrst", "0"), v_fd))
    else:   # the reset drain is the supply port: the supply at FD's level sets FD there (the follower stays saturated)
        sup = [Element("Vdd", ("vdd", "0"), v_fd), *sup[1:]]
    el = [*sup, Element("Vrst", ("rst", "0"), 0.0), Element("Vtg", ("tg", "0"), design.levels.tg_low),
          Element("Vlight0", ("light0", "0"), 0.0), Element("Vshg", ("shg", "0"), vdd), *bias(design),
          instance(cell, 0),
          mosfet("ld0", "col0", "nbias", "0", "0", c.load_w, c.load_l, t), Element("Ccol0", ("col0", "0"), c.cap),
          mosfet("shr0", "col0", "shg", "vshr0", "0", c.sw_w, c.sw_l, t), Element("Cshr0", ("vshr0", "0"), c.sh_cap)]
    return cds_deck(design, cell, el, Noise("vshr0", "rs", vdd, *F_RANGE, POINTS), "role_noise",
                    options=(*NOISE_OPTIONS, RSHUNT))


#: 1 fS from every node to ground in the .noise deck: a pinned photodiode's charge node has no
#: conductance of its own in DC (an empty well's potential is undefined), which made the operating
#: point fail at some conditions (ss -20 degC -10 %); its 2 fA at FD and its thermal noise (corner
#: below 0.1 Hz, removed by the CDS weighting) change the figure by < 1e-6
RSHUNT = ("rshunt", 1e15)


def cds_variance(f, psd, dt: float) -> float:
    """V^2 of the CDS difference of two samples ``dt`` apart of a noise of one-sided PSD ``psd`` (V^2/Hz)."""
    w = 2.0 * (1.0 - np.cos(2 * np.pi * f * dt))
    return float(np.trapezoid(psd * w, f))


def noise(design, draw=None, backend: str = "batch") -> dict:
    from ..camera.spicenoise import run_noise
    from ..circuits.cds import timing_of
    from ..errors import PixelkitError, SimulationError
    op = read_point(design, backend)
    net = apply_draw(deck(design, op["v_fd"]), design, draw)
    try:
        r = run_noise(net)
    except SimulationError:
        raise
    except PixelkitError as exc:   # ngspice's own failure: recorded at this condition, not a user error
        raise SimulationError(net.title, ".noise", str(exc), what=f"the read chain of {design.name} at its read "
                              f"point (FD {op['v_fd']:.3g} V)") from None
    dt = timing_of(design).cds_interval
    var = cds_variance(r["f"], r["psd"], dt)
    return {"sigma_V": float(np.sqrt(var)), "sample_V": r["total_V"], "dt_s": dt, **op}
