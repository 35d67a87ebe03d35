"""The read noise again, in the time domain: the true-CDS read simulated with each device's noise as a
transient noise source (ngspice TRNOISE), the spread of the CDS outputs of many reads.

An independent path to ``rolepix.noise``'s figure: nothing of the frequency-domain weighting is used
- the column's settling, the sample-and-hold switches opening, the two samples' correlation, all
come from the transient. What both share is each device's noise *level*, from BSIM4:

- devices in saturation (the source follower, the column load and its mirror) get a source in series
  with their gate, of the gate-referred PSD S_vg(f) = S_w + K / f^ef that ``.noise`` gives for the
  device alone at its current (a follower deck of it: the input-referred noise);
- switches in their linear region (row select, the sample-and-hold switches) get a source in series
  with their drain of 4 k T R_on, R_on from an operating point at their read levels.

A white TRNOISE source of rms NA drawn every NT has the one-sided PSD 2 NA^2 NT (below 1 / NT; ngspice's
linear interpolation rolls it off above); its 1/f^alpha part of amplitude NAMP has a level the kit
calibrates once per NT (``flicker_scale``: one source alone, its Welch PSD). Left out: the reset
switch (its kT/C on FD is in both samples: ``fd_reset_check`` shows the CDS cancelling such an
offset), the pixel's junction shot noise.

Which devices get which source is the cell's ``noise`` table (the 4T generator's: SF at its gate, RS
at its drain) and the bench's column (load and mirror at the gate, S/H switches at the drain).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..constants import K_B
from ..spice.netlist import Element, Netlist, Trnoise, Tran

#: TRNOISE sample interval: resolves the S/H switch's R_on C_SH (~5 ns) and the column (~50 ns)
NT = 2e-9
#: the column devices and how their noise enters (bench element name prefixes)
COLUMN = (("ld", "gate"), ("bias", "gate"), ("shr", "drain"), ("shs", "drain"))


def _svg(design, w, l, i_d, v_g, backend) -> tuple[float, float]:
    """(S_w V^2/Hz, K V^2 Hz^(ef-1)) of the gate-referred noise of a w x l NMOS carrying ``i_d``."""
    from ..camera.spicenoise import run_noise
    from ..circuits.devices import mosfet
    from ..circuits.noisebench import NOISE_OPTIONS, Noise
    t = design.tech
    el = (mosfet("f", "vdd", "g", "s", "0", w, l, t), Element("Vdd", ("vdd", "0"), t.supply),
          Element("Ib", ("s", "0"), i_d))
    net = Netlist(title="trn_svg", elements=el, analysis=Noise("s", "g", v_g, 1.0, 1e9, 10),
                  includes=t.models.includes(design.corner or None), temperature_C=design.temperature - 273.15,
                  options=NOISE_OPTIONS)
    r = run_noise(net)
    f, s = r["f"], r["psd_in"]
    s_w = float(np.median(s[(f >= 1e7) & (f <= 1e8)]))
    ef = design.tech.mos.ef
    low = (f >= 10) & (f <= 1e3)
    k = float(np.mean((s[low] - s_w) * f[low] ** ef))
    return s_w, max(k, 0.0)


def _r_on(design, w, l, v_g, v_s, backend) -> float:
    """Channel resistance (Ohm) of a w x l NMOS switch, gate at ``v_g``, source and drain near ``v_s``."""
    from ..circuits.devices import mosfet
    from ..spice import simulate
    from ..spice.netlist import Op
    t = design.tech
    el = (mosfet("s", "d", "g", "src", "0", w, l, t), Element("Vg", ("g", "0"), v_g),
          Element("Vs", ("src", "0"), v_s), Element("Vd", ("d", "0"), v_s + 1e-3))
    r = simulate(Netlist(title="trn_ron", elements=el, analysis=Op(), includes=t.models.includes(design.corner or None),
                         temperature_C=design.temperature - 273.15), backend=backend)
    return float(1e-3 / -r["i(vd)"][0])


def flicker_scale(alpha: float, nt: float = NT, backend: str = "batch") -> float:
    """kappa: a TRNOISE 1/f^alpha source of amplitude NAMP has the one-sided PSD kappa NAMP^2 / f^alpha
    (ngspice's generator; measured on 4 sources of 2000 NT x 64 samples each, Welch PSD)."""
    from scipy.signal import welch
    from ..spice import simulate
    n, dur = 4, 4e-4 * nt / 2e-9
    el = tuple(Element(f"V{k}", (f"n{k}", "0"), Trnoise(0.0, 0.0, nt, alpha, 1e-3)) for k in range(n))
    r = simulate(Netlist(title="trn_flicker_scale", elements=el, analysis=Tran(nt, dur, 0.0, nt),
                         options=(("seed", 3),)), backend=backend)
    tt = np.arange(0.0, dur, nt)
    ps = []
    for k in range(n):
        f, p = welch(np.interp(tt, r.time, r[f"v(n{k})"]), fs=1 / nt, nperseg=2 ** 14)
        ps.append(p)
    f, p = f[1:], np.mean(ps, axis=0)[1:]
    band = (f > 50 / dur) & (f < 0.02 / nt)
    return float(np.mean(p[band] * f[band] ** alpha) / 1e-6)


def sources(design, op: dict, backend: str = "batch") -> dict:
    """{device: Trnoise} of the cell's and the column's noisy devices at the read point ``op``."""
    cell, c, dev = design.cell(), design.column, design.devices
    t, ef = design.temperature, design.tech.mos.ef
    kappa = flicker_scale(ef, NT, backend)
    x = "X" if design.tech.mos.kind == "subckt" else "M"
    sizes = {"sf": (dev.sf_w, dev.sf_l), "rs": (dev.rs_w, dev.rs_l), "ld": (c.load_w, c.load_l),
             "bias": (c.load_w, c.load_l), "shr": (c.sw_w, c.sw_l), "shs": (c.sw_w, c.sw_l)}
    out = {}
    if not cell.noise:
        from ..errors import ConfigError
        raise ConfigError(cell.source, "noise", None, "a cell that names its noisy devices (the 4T generator's); "
                          "the .noise figure covers any cell")
    for name, kind in (*cell.noise, *((x + n, k) for n, k in COLUMN)):
        w, l = sizes[name[1:]]
        if kind == "gate":
            s_w, k = _svg(design, w, l, c.bias, op["v_fd"], backend)
            out[name] = ("gate", Trnoise(0.0, (s_w / (2 * NT)) ** 0.5, NT, ef if k else 0.0, (k / kappa) ** 0.5))
        else:
            r_on = _r_on(design, w, l, design.tech.supply, op["v_col"], backend)
            out[name] = ("drain", Trnoise(0.0, (4 * K_B * t * r_on / (2 * NT)) ** 0.5, NT))
    return out


def _noisy(elements, noisy: dict) -> list:
    """``elements`` with a series TRNOISE source at the gate or drain of each device of ``noisy``
    (matched by name, or by prefix for a column's numbered devices)."""
    out = []
    for e in elements:
        key = next((k for k in noisy if e.name == k or (e.name.startswith(k) and e.name[len(k):].isdigit())), None)
        if key is None:
            out.append(e)
            continue
        kind, src = noisy[key]
        d, g, s, b = e.nodes
        if kind == "gate":
            out += [Element(f"Vn{e.name}", (f"{e.name}_g", g), src), replace(e, nodes=(d, f"{e.name}_g", s, b))]
        else:
            out += [Element(f"Vn{e.name}", (d, f"{e.name}_d"), src), replace(e, nodes=(f"{e.name}_d", g, s, b))]
    return out


def deck(design, noisy: dict, columns: int, frames: int, seed: int) -> Netlist:
    """The dark pixel read ``frames`` times on ``columns`` columns, every device source of ``noisy`` on."""
    from ..circuits.cds import cds_bench
    from .signal import flush_exposure
    cell = design.cell()
    t0 = flush_exposure(design)
    ex = [t0] * (frames + 1)
    net = cds_bench(design, cell, ex, [[0.0] * len(ex)] * columns, title=f"role_trnoise_{columns}x{frames}_{seed}")
    sub = replace(cell.subckt, elements=tuple(_noisy(cell.subckt.elements, noisy)))
    return replace(net, elements=tuple(_noisy(net.elements, noisy)), subckts=(*cell.support, sub),
                   analysis=Tran(NT, net.analysis.stop, 0.0, NT, uic=True), options=(*net.options, ("seed", seed)))


def read_noise(design, columns: int = 8, frames: int = 6, seed: int = 1, backend: str = "batch") -> dict:
    """sigma (V) of the CDS output over ``columns`` x ``frames`` reads, with its 95 % interval."""
    from scipy.stats import chi2
    from ..circuits.cds import timing_of
    from ..measure.cds import cds
    from ..spice import simulate
    from .noise import read_point
    op = read_point(design, backend)
    noisy = sources(design, op, backend)
    net = deck(design, noisy, columns, frames, seed)
    r = simulate(net, backend=backend)
    tm, st, ex = timing_of(design), net.meta["frames"]["starts"], net.meta["frames"]["exposures"]
    x = np.array([[cds(r, tm, ex, st, k, f) for f in range(1, frames + 1)] for k in range(columns)])
    x = x - x.mean(axis=1, keepdims=True)   # each column's own offset (its devices' mean) is not noise
    n = x.size - columns
    var = float((x ** 2).sum() / n)
    lo, hi = (n * var / chi2.ppf(q, n) for q in (0.975, 0.025))
    return {"sigma_V": var ** 0.5, "interval_V": [lo ** 0.5, hi ** 0.5], "reads": int(x.size),
            "sources": {k: {"kind": kind, "na_V": s.na, "namp": s.namp} for k, (kind, s) in noisy.items()}}


def fd_reset_check(design, columns: int = 4, frames: int = 6, na: float = 5e-3, seed: int = 2,
                   backend: str = "batch") -> dict:
    """True CDS against a reset offset: the reset drain, regulated 1.3 V below the reset gate's level (a
    hard reset: FD follows the drain), carries white noise of ``na`` rms redrawn every half row time,
    so every FD reset lands on another level (what kT/C does to a real FD). Each read's reset sample
    moves with it; the CDS output, reset sample minus signal sample of the same reset, must not:
    ``{"reset_sigma_V", "cds_sigma_V"}`` over ``columns`` x ``frames`` dark reads (each column's own
    mean removed). Needs a cell with a reset-drain role. (With the drain at the gate level the reset is
    soft: FD settles below the gate by a threshold whatever the drain does, and nothing moves.)"""
    from ..circuits.cds import gate_high
    design = replace(design, levels=replace(design.levels, v_rst=gate_high(design) - 1.3))
    from ..circuits.cds import cds_bench, timing_of
    from ..measure.cds import samples
    from ..spice import simulate
    from .signal import flush_exposure
    cell = design.cell()
    cell.require(("vrst",), "the reset-offset check")
    tm = timing_of(design)
    t0 = flush_exposure(design)
    ex = [t0] * (frames + 1)
    net = cds_bench(design, cell, ex, [[0.0] * len(ex)] * columns, title=f"role_fdreset_{columns}x{frames}_{seed}")
    el = tuple(replace(e, value=Trnoise(e.value, na, tm.t_row / 2)) if e.name == "Vrstd" else e for e in net.elements)
    net = replace(net, elements=el, options=(*net.options, ("seed", seed)))
    r = simulate(net, backend=backend)
    st = net.meta["frames"]["starts"]
    s = np.array([[samples(r, tm, ex, st, k, f) for f in range(1, frames + 1)] for k in range(columns)])
    rst, cds = s[..., 0], s[..., 0] - s[..., 1]
    rst, cds = rst - rst.mean(axis=1, keepdims=True), cds - cds.mean(axis=1, keepdims=True)
    n = rst.size - columns
    return {"reset_sigma_V": float(np.sqrt((rst ** 2).sum() / n)), "cds_sigma_V": float(np.sqrt((cds ** 2).sum() / n)),
            "reads": int(rst.size)}
