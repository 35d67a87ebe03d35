"""EKV parameters of one NMOS size, fitted to the model library's own operating points.

One DC deck: ``POINTS`` copies of the device as a source follower (drain at the supply,
bulk at ground, an ideal current sinking I from the source, the gate at V_G), over the
gate voltages and currents of a pixel follower (V_G 1.1 - 2.4 V, 50 nA - 4 uA: weak to
moderate inversion at the pixel's sizes). ``fit`` returns the ``physics.sf.Ekv`` whose
source voltages match ngspice's in least squares (they do within a few mV). Cached by the
engine, so a design's models fit it once.
"""
from __future__ import annotations

import numpy as np

from ..circuits.devices import mosfet
from ..physics.sf import Ekv
from ..spice.netlist import Element, Netlist, Op

V_G = (1.1, 1.4, 1.7, 2.0, 2.4)
CURRENTS = (50e-9, 200e-9, 800e-9, 4e-6)


def _deck(tech, w, l, temperature_K, corner=None):
    el = [Element("Vdd", ("vdd", "0"), tech.supply)]
    for k, vg in enumerate(V_G):
        el.append(Element(f"Vg{k}", (f"g{k}", "0"), vg))
        for j, i in enumerate(CURRENTS):
            el.append(mosfet(f"m{k}_{j}", "vdd", f"g{k}", f"s{k}_{j}", "0", w, l, tech))
            el.append(Element(f"I{k}_{j}", (f"s{k}_{j}", "0"), i))
    return Netlist(title="ekv_fit", elements=tuple(el), analysis=Op(), includes=tech.models.includes(corner),
                   temperature_C=temperature_K - 273.15)


def source_voltages(tech, w, l, temperature_K, backend="batch", corner=None) -> np.ndarray:
    """ngspice's follower outputs, [gate voltage, current]."""
    from ..spice import simulate
    r = simulate(_deck(tech, w, l, temperature_K, corner), backend=backend)
    return np.array([[float(r[f"v(s{k}_{j})"][0]) for j in range(len(CURRENTS))] for k in range(len(V_G))])


_FITS: dict = {}


def _fit(tech, w, l, temperature_K, backend, corner=None):
    from scipy.optimize import least_squares
    vs = source_voltages(tech, w, l, temperature_K, backend, corner)
    ok = vs > 0.05          # the source must be above ground for the follower to be a follower

    def resid(p):
        m = Ekv(*p)
        pred = np.array([[m.v_s(vg, i, w / l, temperature_K) for i in CURRENTS] for vg in V_G])
        return (pred - vs)[ok]
    p0 = np.array([tech.mos.vth_n, 0.6, 0.8, 2e-4])
    r = least_squares(resid, p0, bounds=([0.2, 0.05, 0.3, 1e-6], [1.5, 2.0, 1.5, 1e-2]), x_scale=[0.1, 0.1, 0.1, 1e-4])
    return Ekv(*map(float, r.x)), float(np.sqrt(np.mean(r.fun ** 2)))


def fit(tech, w: float, l: float, temperature_K: float, backend: str = "batch", corner: str | None = None
        ) -> tuple[Ekv, float]:
    """(EKV parameters, rms error of the fitted source voltages in V) of a w x l NMOS of ``tech`` (at the model
    library's ``corner``; default its default corner)."""
    key = (tech.name, tech.source, w, l, temperature_K, backend, corner)
    if key not in _FITS:
        _FITS[key] = _fit(tech, w, l, temperature_K, backend, corner)
    return _FITS[key]


def models_for(design) -> dict:
    """The fitted EKV parameters of the pixel's follower, column load and row switch ({"sf", "load", "rs"}),
    which the analytic models in ``physics.sf`` and ``physics.noise`` take as an argument (they sit below the
    simulator and never fit anything themselves)."""
    dev, t, temp = design.pixel.devices, design.tech, design.temperature
    return {k: fit(t, getattr(dev, f"{k}_w"), getattr(dev, f"{k}_l"), temp)[0] for k in ("sf", "load", "rs")}
