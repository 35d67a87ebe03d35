"""The floating diffusion (FD): its capacitance from the devices, charge sharing, output CG.

FD is the storage node of the 5T global-shutter pixel. What the netlist hangs on
it, and so what the analytic node holds:

- the TG drain and the RST source diffusions: bottom junction (area), field
  sidewall (perimeter minus the gate edge) and gate-edge sidewall, all with the
  technology's MOS junction parameters (the C(V) of ``junction``), plus the gate
  overlap ``cgso W`` of each switch (their gates sit at a fixed level in storage);
- the SF gate: the drain overlap ``cgso W`` to VDD, and the gate-source
  capacitance (2/3 Cox W L + cgso W in saturation) bootstrapped by the follower:
  only ``(1 - A_sf)`` of it loads FD (Miller).

Charge sharing: TG conducts in its linear region during the transfer, so the PD
node (PD junction + EC/TG diffusions, ``subpixel.pd_node(parasitics=True)``) and
FD settle to one voltage; a photo-charge dQ moves both by dQ / (C_PD + C_FD), and
FD keeps that voltage when TG opens. The column signal (reset level - signal
level, NCDS) moves by ``A_sf`` times that. Hence

    CG_PD  = q / C_PD                       (the thesis's eq. 3.6)
    CG_FD  = q / (C_PD,node + C_FD)         (charge sharing)
    CG_out = A_sf q / (C_PD,node + C_FD)    (column, V/e-)

``A_sf``, the small-signal gain of the SF with its column load, comes from the
BSIM4 device models at the read operating point (``circuits.testbench.sf_gain``):
the kit has no closed form for those models. Everything else is closed form.

Storage: FD leaks with the kit's one dark-current law (``dark``) on the FD
diffusions, and collects a parasitic photocurrent I_ph / gse (the design's
``pixel.gse`` = eta_pd / eta_FD, a charge ratio set by the shielding) while it waits.
"""
from __future__ import annotations

from ..circuits.geometry import diffusion
from ..constants import Q
from .dark import dark_scale
from .junction import Junction, Node


def mos_junctions(tech) -> tuple[Junction, Junction]:
    """(bottom + field sidewall, gate-edge sidewall) junctions of the technology's MOS diffusions."""
    mos = tech.mos
    return (Junction(mos.cj, mos.mj, mos.pb, mos.cjsw, mos.mjsw, mos.pbsw),
            Junction(0.0, 0.5, 1.0, mos.cjswg, mos.mjswg, mos.pbswg))


def switch_side(w: float, tech) -> tuple[tuple, float]:
    """Junction terms and fixed overlap C (F) that one source/drain of width ``w`` adds to a node."""
    body, edge = mos_junctions(tech)
    a, p = diffusion(w, tech.mos.diff_ext)
    return ((a, p - w, body), (0.0, w, edge)), tech.mos.cgso * w


def sf_gate(design, a_sf: float) -> float:
    """Capacitance (F) the SF gate adds to FD: drain overlap + (1 - A_sf) x gate-source."""
    dev, mos = design.pixel.devices, design.tech.mos
    c_gs = 2.0 / 3.0 * mos.cox * dev.sf_w * dev.sf_l + mos.cgso * dev.sf_w
    return mos.cgso * dev.sf_w + (1.0 - a_sf) * c_gs


def fd_node(design, a_sf: float) -> Node:
    """C(V) of the floating diffusion (reverse bias V of its junctions)."""
    dev, tech = design.pixel.devices, design.tech
    terms, c_fixed = [], sf_gate(design, a_sf)
    for w in (dev.tg_w, dev.rst_w):
        t, c = switch_side(w, tech)
        terms += t
        c_fixed += c
    return Node(tuple(terms), c_fixed)


def fd_diffusion(design) -> tuple[float, float]:
    """(area m^2, perimeter m) of the FD's junctions (TG drain + RST source)."""
    dev, ext = design.pixel.devices, design.tech.mos.diff_ext
    a1, p1 = diffusion(dev.tg_w, ext)
    a2, p2 = diffusion(dev.rst_w, ext)
    return a1 + a2, p1 + p2


def leakage(design, temperature_K: float | None = None) -> float:
    """FD junction leakage (A): the PD's dark-current densities and doubling law on the FD diffusions.

    The technology gives one generation-current density pair (``photodiode.dark_*``);
    the FD's n+/p-sub junction is assumed to leak alike (EFFECTS.md row 2: mV/s to
    tens of mV/s at room temperature on a few fF).
    """
    pd = design.tech.photodiode
    a, p = fd_diffusion(design)
    t = design.temperature if temperature_K is None else temperature_K
    return (pd.dark_area * a + pd.dark_perimeter * p) * dark_scale(t, pd)


def response(design, which: str, a_sf: float, v_bias: float | None = None) -> dict:
    """PD-referred and output-referred conversion gain of ``which`` subpixel at ``v_bias``.

    ``v_bias`` (default: the design's PD reset level) is the reverse bias of the PD node
    and FD at which the small-signal capacitances are taken.
    """
    from .subpixel import pd_node
    v = design.pixel.v_pd_reset if v_bias is None else v_bias
    c_pd = float(pd_node(design, which).capacitance(v))
    c_node = float(pd_node(design, which, parasitics=True).capacitance(v))
    c_fd = float(fd_node(design, a_sf).capacitance(v))
    c_tot = c_node + c_fd
    return {"v_bias_V": v, "c_pd_F": c_pd, "c_pd_node_F": c_node, "c_fd_F": c_fd, "c_total_F": c_tot,
            "cg_pd_V_per_e": Q / c_pd, "sharing": c_node / c_tot, "cg_fd_V_per_e": Q / c_tot,
            "a_sf": a_sf, "cg_out_V_per_e": a_sf * Q / c_tot}


def pls_current(design, i_ph: float) -> float:
    """Parasitic photocurrent (A) on FD for a PD photocurrent ``i_ph``: i_ph / gse.

    ``pixel.gse`` is the charge ratio eta_pd / eta_FD the shielding gives. The
    signal GSE a camera measures (dS/dt_exp over dS/dt_wait, EFFECTS.md row 1) is
    smaller by C_FD / C_total: a charge on the small FD moves it more (``signal_gse``).
    """
    return i_ph / design.pixel.gse


def signal_gse(design, which: str, a_sf: float) -> float:
    """GSE on the signal: gse x C_FD / (C_PD,node + C_FD)."""
    r = response(design, which, a_sf)
    return design.pixel.gse * r["c_fd_F"] / r["c_total_F"]


def storage_signal(design, which: str, a_sf: float, i_ph: float, t_wait: float,
                   temperature_K: float | None = None) -> float:
    """Column signal (V) the FD adds while it waits ``t_wait``: leakage + parasitic light."""
    r = response(design, which, a_sf)
    i = leakage(design, temperature_K) + pls_current(design, i_ph)
    return a_sf * i * t_wait / r["c_fd_F"]
