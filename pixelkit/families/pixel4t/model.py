"""The 4T pixel's closed forms: what the SPICE figures of ``rolepix`` are checked against.

- **FD capacitance**: the TG drain and RST source junctions (bottom + field sidewall, gate edge: the
  technology's MOS junction parameters, C(V) at FD's reverse bias), the TG overlap as the generator
  writes it, RST's overlap at its gate-off bias, and the source follower's gate: the drain overlap
  plus ``(1 - A_sf)`` of the gate-source capacitance (Miller bootstrap), as ``physics.fd`` builds the
  dual pixel's FD from the same primitives; in the post-layout view, FD's extracted wiring (``wiring``).
- **Conversion gain**: ``CG = A_sf q / C_FD`` at FD's level during the read, A_sf the follower with
  its row select and column load from two SPICE operating points (the kit has no closed form for
  BSIM4's gain), the sample-and-hold's gain 1.
- **Full well**: the PPD's, ``physics.ppd.Ppd.full_well`` (C_PPD V_pin in the dark, plus the
  logarithmic light term), and the output's swing over CG.
- **Lag**: ``physics.ppd.Ppd.residual`` over the read's transfer, the next shutter's and the next
  read's (``lag_electrons``).
- **Dark current**: I_gen + I_dif of the PPD at the temperature.
"""
from __future__ import annotations

from ...constants import Q
from ...physics.junction import Node
from ...physics.nodes import overlap, switch_side


def tg_channel(design):
    """The TG channel: the technology's NMOS fitted (EKV, ``techfit.ekv``) at the TG's size and the design's
    temperature and corner."""
    from ...physics.ppd import Channel
    from ...techfit.ekv import fit
    dev = design.devices
    ekv, _rms = fit(design.tech, dev.tg_w, dev.tg_l, design.temperature, corner=design.corner or None)
    return Channel(ekv.vt0, ekv.gamma, ekv.phi, ekv.kp, dev.tg_w / dev.tg_l)


def a_sf(design, v_fd: float, dv: float = 0.01, backend: str = "batch") -> float:
    """dV_col / dV_FD of the follower, its row select (on) and the column load, two SPICE operating points."""
    from ...circuits.devices import mosfet
    from ...spice import simulate_many
    from ...spice.netlist import Element, Netlist, Op
    dev, c, t = design.devices, design.column, design.tech

    def deck(v, title):
        el = (Element("Vdd", ("vdd", "0"), t.supply), Element("Vfd", ("fd", "0"), v),
              Element("Vrs", ("rs", "0"), t.supply), Element("Ibias", ("vdd", "nbias"), c.bias),
              mosfet("bias", "nbias", "nbias", "0", "0", c.load_w, c.load_l, t),
              mosfet("sf", "vdd", "fd", "sfo", "0", dev.sf_w, dev.sf_l, t),
              mosfet("rs", "sfo", "rs", "col", "0", dev.rs_w, dev.rs_l, t),
              mosfet("ld", "col", "nbias", "0", "0", c.load_w, c.load_l, t))
        return Netlist(title=title, elements=el, analysis=Op(), includes=t.models.includes(design.corner or None),
                       temperature_C=design.temperature - 273.15)
    lo, hi = simulate_many([deck(v_fd - dv, "p4t_sf_lo"), deck(v_fd + dv, "p4t_sf_hi")], backend=backend)
    return float((hi["v(col)"][0] - lo["v(col)"][0]) / (2 * dv))


def fd_capacitance(design, a: float, v_fd: float) -> float:
    """C_FD (F) at FD's level ``v_fd`` with the follower's gain ``a`` (module docstring)."""
    from ...circuits.pixel4t import tg_overlap
    dev, tech, mos = design.devices, design.tech, design.tech.mos
    terms, c = [], tg_overlap(design)
    for w, v_ov in ((dev.tg_w, None), (dev.rst_w, -v_fd)):
        t, c_ov = switch_side(w, tech, -v_fd if v_ov is None else v_ov)
        terms += t
        c += c_ov if v_ov is not None else 0.0     # the TG's overlap is the generator's element
    c_gs = 2.0 / 3.0 * mos.cox * dev.sf_w * dev.sf_l + overlap(dev.sf_w, 1.0, mos)
    c += overlap(dev.sf_w, v_fd - tech.supply, mos) + (1.0 - a) * c_gs
    return float(Node(tuple(terms), c).capacitance(v_fd)) + wiring(design, a)


def wiring(design, a: float) -> float:
    """FD's extracted wiring (F) in the post-layout view (``layout.pixel4t.extracted``; 0 on the schematic):
    every coupling of FD, those to the follower's source and the column counted 1 - A_sf of themselves (they
    follow FD)."""
    pl = getattr(design, "post_layout", None)
    if pl is None:
        return 0.0
    return sum(c * ((1.0 - a) if ({x, y} - {"fd"}) <= {"sfo", "col"} else 1.0)
               for x, y, c in pl.couplings if "fd" in (x, y))


def conversion_gain(design, v_fd: float, backend: str = "batch") -> dict:
    """CG (V/e-) at the column with its parts."""
    a = a_sf(design, v_fd, backend=backend)
    c_fd = fd_capacitance(design, a, v_fd)
    return {"a_sf": a, "c_fd_F": c_fd, "cg_fd_V_per_e": Q / c_fd, "cg_V_per_e": a * Q / c_fd}


def lag_electrons(ppd, q_bright: float, t_tg: float, v_tg: float) -> dict:
    """Electrons of the bright frame's read, and of the dark frame after it (barrier-limited transfer):
    the read leaves r1, the next shutter r2 of it, the next read transfers r2 less what it leaves."""
    r1 = ppd.residual(q_bright, t_tg, v_tg)
    r2 = ppd.residual(r1, t_tg, v_tg)
    r3 = ppd.residual(r2, t_tg, v_tg)
    return {"signal_e": (q_bright - r1) / Q, "lag_e": (r2 - r3) / Q, "left_after_read_e": r1 / Q}


def ktc_electrons(c: float, temperature_K: float) -> float:
    """The reset noise (e- rms) a non-correlated read of FD would carry: sqrt(k T C) / q; true CDS cancels it."""
    from ...constants import K_B
    return (K_B * temperature_K * c) ** 0.5 / Q


def figures(design, backend: str = "batch") -> dict:
    """The closed-form table (``pixelkit models``): the PPD, its transfer at the design's TG level, FD,
    the conversion gain at FD's reset-drain level (A_sf from two SPICE operating points), kT/C."""
    from ...circuits.cds import tg_high
    from ...circuits.pixel4t import ppd_model
    p = ppd_model(design, tg_channel(design))
    v_tg = tg_high(design)
    v_fd = design.levels.v_rst_for(design.tech.supply) - 1.0   # a soft reset leaves FD ~1 V below its drain
    cg = conversion_gain(design, v_fd, backend)
    n_half = 0.5 * p.full_well()
    lag = lag_electrons(p, n_half, design.timing.t_tg, v_tg)
    return {"c_ppd_fF": p.c * 1e15, "v_pin_V": p.v_pin, "full_well_dark_e": p.full_well() / Q,
            "phi_b_V": p.phi_b(v_tg), "barrier_V": p.v_pin - p.phi_b(v_tg), "emission_tau_s": p.tau(v_tg),
            "lag_after_half_well_e": lag["lag_e"], "dark_current_e_per_s": (p.i_gen + p.i_dif) / Q,
            "v_fd_assumed_V": v_fd, "a_sf": cg["a_sf"], "c_fd_fF": cg["c_fd_F"] * 1e15,
            "conversion_gain_uV_per_e": cg["cg_V_per_e"] * 1e6,
            "fd_ktc_e": ktc_electrons(cg["c_fd_F"], design.temperature)}
