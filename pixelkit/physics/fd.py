"""The floating diffusion (FD): its capacitance from the devices, charge sharing, output CG.

FD is the storage node of the 5T global-shutter pixel. What the netlist hangs on
it, and so what the analytic node holds:

- the TG drain and the RST source diffusions: bottom junction (area), field
  sidewall (perimeter minus the gate edge) and gate-edge sidewall, all with the
  technology's MOS junction parameters (the C(V) of ``junction``), plus the gate
  overlap of each switch (their gates sit at 0 V in storage and readout);
- the SF gate: the drain overlap to VDD, and the gate-source capacitance
  (2/3 Cox W L + the source overlap, in saturation) bootstrapped by the
  follower: only ``(1 - A_sf)`` of it loads FD (Miller).

An overlap is ``cgso W`` plus the bias-dependent LDD part of BSIM4's capmod 2,
``cgsl W (1 - 1/sqrt(1 - 4 V_ov / ckappa))`` for an overlap voltage V_ov < 0 (gate
below the diffusion) and the full ``cgsl W`` above; it is taken at the node's bias.
Without it the FD is 10 % short of what SPICE's devices put on it (0.16 fF of 2.0).

Charge sharing: TG conducts in its linear region during the transfer, so the PD
node (PD junction + EC/TG diffusions, ``nodes.pd_node(parasitics=True)``) and
FD settle to one voltage; a photo-charge dQ moves both by dQ / (C_PD + C_FD), and
FD keeps that voltage when TG opens. The column signal (reset level - signal
level, NCDS) moves by ``A_sf`` times that. Hence

    CG_PD  = q / C_PD                       (the thesis's [Thesis2019] eq. 3.6)
    CG_FD  = q / (C_PD,node + C_FD)         (charge sharing)
    CG_out = A_sf q / (C_PD,node + C_FD)    (column, V/e-)

``A_sf``, the small-signal gain of the SF with its column load, comes from the
BSIM4 device models at the read operating point (``camera.spicenoise.sf_gain``, a SPICE run the caller makes):
the kit has no closed form for those models. Everything else is closed form.

Storage: FD leaks through its diffusions by the device models' junction law
(``dark.diffusion_leakage``: BSIM4's, which SPICE applies to the same diffusions), and collects a parasitic photocurrent I_ph / gse (the design's
``gse``: ``pixel.gse`` or the collection model's, a charge ratio eta_pd / eta_FD) while it waits.
"""
from __future__ import annotations

from .geometry import diffusion
import numpy as np

from ..constants import Q
from .dark import diffusion_leakage
from .junction import Node
from .nodes import overlap, pd_node, switch_side, wiring


def sf_gate(design, a_sf: float, v_fd: float | None = None) -> float:
    """Capacitance (F) the SF gate adds to FD: drain overlap + (1 - A_sf) x gate-source."""
    dev, mos = design.pixel.devices, design.tech.mos
    v = design.pixel.v_pd_reset if v_fd is None else v_fd
    c_gs = 2.0 / 3.0 * mos.cox * dev.sf_w * dev.sf_l + overlap(dev.sf_w, 1.0, mos)
    return overlap(dev.sf_w, v - design.tech.supply, mos) + (1.0 - a_sf) * c_gs


def fd_node(design, a_sf: float, v_fd: float | None = None, which: str = "primary") -> Node:
    """C(V) of the floating diffusion (reverse bias V of its junctions); overlaps taken at ``v_fd``
    (default the PD reset level), with TG and RST gates at 0 V. Post-layout (``design.post_layout``)
    the extracted wiring of ``which`` subpixel's FD is added: its couplings to the nodes that
    follow FD through the SF (``sfo``, the column line) bootstrapped by A_sf like the SF gate."""
    dev, tech = design.pixel.devices, design.tech
    v = design.pixel.v_pd_reset if v_fd is None else v_fd
    terms, c_fixed = [], sf_gate(design, a_sf, v) + wiring(design, which, "fd", a_sf)
    for w in (dev.tg_w, dev.rst_w):
        t, c = switch_side(w, tech, -v)
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
    """FD leakage (A): its TG drain and RST source diffusions (``diffusion_leakage``)."""
    dev = design.pixel.devices
    t = design.temperature if temperature_K is None else temperature_K
    return sum(diffusion_leakage(w, design.tech, t) for w in (dev.tg_w, dev.rst_w))


def pd_switch_leakage(design, temperature_K: float | None = None) -> float:
    """What the EC and TG source diffusions add to the PD node's dark current (A)."""
    dev = design.pixel.devices
    t = design.temperature if temperature_K is None else temperature_K
    return sum(diffusion_leakage(w, design.tech, t) for w in (dev.ec_w, dev.tg_w))


def transfer(design, which: str, a_sf: float, sf_models: dict, v: float | None = None) -> dict:
    """The photo-charge's way to the read, in three stages, each with the capacitances it sees.

    1. *Transfer* (TG on, RS off): the PD node and FD are one node through TG's channel, so the
       charge spreads over ``C_T = C_PD,node + C_FD,store + C_ch`` - the channel's gate capacitance
       ``C_ch = Cox W L`` of TG included, and both TG overlaps at their gate-high value.
    2. *TG turns off* (the TG charge split): TG opens when its gate falls to the node's voltage plus
       its threshold, so a signal dV keeps it on for a further gate fall (1 + eta) dV (eta: the body
       factor at the node). During that fall the signal run's node still follows the gate through
       ``C_g = C_ch + 2 C_ov`` over C_T, while a dark pixel's FD, already alone, follows it through
       TG's FD-side overlap over C_FD,store: the FD keeps ``1 + (1 + eta)(C_g / C_T - C_ov / C_FD,store)``
       of its transfer voltage (below 1 for a large PD, above 1 for a small one).
    3. *RS turns on* (the select switch): FD's charge stays, its capacitance changes. Stored (RS
       off) the follower's source floats: its gate sees its depletion capacitance
       ``Cox W L (n - 1) / n`` (weak inversion); selected, the gate-source capacitance bootstrapped,
       ``(1 - A_sf)(2/3 Cox W L + C_ov)`` (``sf_gate``): FD's voltage is ``C_FD,store / C_FD,read`` of the stored one.
       Post-layout, RS's rise kicks the floating FD up by ``C(fd, rs) V_dd / C_FD,store`` through the
       extracted wiring, and C_FD,read is taken there.

    ``eta`` and ``n`` are those of the pixel's NMOS at the node's voltage: the follower's EKV parameters
    (``sf_models["sf"]``, ``techfit.ekv.models_for``). The single-capacitance sharing ``q / (C_PD,node + C_FD,read)`` lacks 1 and 3
    and its errors cancel at the read (docs/post-layout.md: each stage against SPICE).
    """
    dev, mos = design.pixel.devices, design.tech.mos
    v = design.pixel.v_pd_reset if v is None else v
    ekv = sf_models["sf"]
    n = ekv.n(ekv.v_p(v))
    eta = ekv.gamma / (2.0 * float(np.sqrt(ekv.phi + v)))
    c_ch = mos.cox * dev.tg_w * dev.tg_l
    ov_on, ov_off = overlap(dev.tg_w, 1.0, mos), overlap(dev.tg_w, -v, mos)
    c_node = float(pd_node(design, which, parasitics=True).capacitance(v))
    c_read = float(fd_node(design, a_sf, v, which).capacitance(v))
    c_gs = 2.0 / 3.0 * mos.cox * dev.sf_w * dev.sf_l + overlap(dev.sf_w, 1.0, mos)
    # post-layout: FD's wiring to the follower's source and to the column line follows FD when selected
    # (counted (1 - A_sf) at the read); stored, the column line is held by its load and the floating
    # source follows the gate by 1 / n
    pl = getattr(design, "post_layout", None)
    w_sfo = w_col = w_rs = 0.0
    for a, b, c in (pl.cells.get(f"pix5t_{which}", ()) if pl is not None else ()):
        if {a, b} == {"fd", "sfo"}:
            w_sfo += c
        elif {a, b} == {"fd", "col"}:
            w_col += c
        elif {a, b} == {"fd", "rs"}:
            w_rs += c
    c_store = (c_read - (1.0 - a_sf) * (c_gs + w_sfo + w_col) + mos.cox * dev.sf_w * dev.sf_l * (n - 1.0) / n
               + w_col + (1.0 - 1.0 / n) * w_sfo)
    # post-layout: RS's rise (0 to the supply) kicks the floating FD through their wiring coupling, its
    # charge kept: the read sees FD w_rs V_dd / C_FD,store higher
    if w_rs:
        v_read = v + w_rs * design.tech.supply / c_store
        c_read = float(fd_node(design, a_sf, v_read, which).capacitance(v_read))
    c_t = float(c_node + c_store + c_ch + 2.0 * (ov_on - ov_off))
    k_tg = float(1.0 + (1.0 + eta) * ((c_ch + 2.0 * ov_on) / c_t - ov_on / c_store))
    k_rs = c_store / c_read
    return {"c_transfer_F": c_t, "c_channel_F": c_ch, "c_fd_store_F": c_store, "c_fd_read_F": c_read,
            "eta": eta, "tg_turnoff": k_tg, "rs_turnon": k_rs, "cg_transfer_V_per_e": Q / c_t,
            "cg_store_V_per_e": Q / c_t * k_tg, "cg_fd_V_per_e": Q / c_t * k_tg * k_rs}


def capacitances(design, which: str, a_sf: float, v_bias: float | None = None) -> dict:
    """The read-time capacitances of ``which`` subpixel at ``v_bias`` (default the PD reset level): the PD
    junction, the PD node (with its switches), FD, and C_PD,node + C_FD (the noise budget's node)."""
    v = design.pixel.v_pd_reset if v_bias is None else v_bias
    c_pd = float(pd_node(design, which).capacitance(v))
    c_node = float(pd_node(design, which, parasitics=True).capacitance(v))
    c_fd = float(fd_node(design, a_sf, v, which).capacitance(v))
    return {"v_bias_V": v, "c_pd_F": c_pd, "c_pd_node_F": c_node, "c_fd_F": c_fd, "c_total_F": c_node + c_fd}


def response(design, which: str, a_sf: float, sf_models: dict, v_bias: float | None = None) -> dict:
    """PD-referred and output-referred conversion gain of ``which`` subpixel at ``v_bias``.

    ``v_bias`` (default: the design's PD reset level) is the reverse bias of the PD node
    and FD at which the small-signal capacitances are taken. CG_FD follows the charge through the
    transfer, TG's turn-off and RS's turn-on (``transfer``; ``sf_models``: ``techfit.ekv.models_for``);
    ``c_total_F`` is the read-time sum C_PD,node + C_FD the noise budget uses.
    """
    c = capacitances(design, which, a_sf, v_bias)
    cg_fd = transfer(design, which, a_sf, sf_models, c["v_bias_V"])["cg_fd_V_per_e"]
    return {**c, "cg_pd_V_per_e": Q / c["c_pd_F"], "sharing": c["c_pd_node_F"] / c["c_total_F"],
            "cg_fd_V_per_e": cg_fd, "a_sf": a_sf, "cg_out_V_per_e": a_sf * cg_fd}


def gse(design, which: str) -> float:
    """The charge ratio eta_pd / eta_FD of ``which`` subpixel: the design's ``pixel.gse`` (geometric
    light), or the collection model's for this subpixel over the scene's spectrum
    (``light.model = "modelled"``: ``layout.pex.lightfigures.with_light`` puts it on the subpixel)."""
    m = getattr(design, which).modelled
    return m["gse"] if m else design.pixel.gse


def pls_current(design, i_ph: float, which: str = "primary") -> float:
    """Parasitic photocurrent (A) on FD for a PD photocurrent ``i_ph``: i_ph / gse.

    ``gse`` is the charge ratio eta_pd / eta_FD the shielding gives. The
    signal GSE a camera measures (dS/dt_exp over dS/dt_wait) is
    smaller by C_FD / C_total: a charge on the small FD moves it more (``signal_gse``).
    """
    return i_ph / gse(design, which)


def signal_gse(design, which: str, a_sf: float) -> float:
    """GSE on the signal: gse x C_FD / (C_PD,node + C_FD)."""
    r = capacitances(design, which, a_sf)
    return gse(design, which) * r["c_fd_F"] / r["c_total_F"]


def storage_signal(design, which: str, a_sf: float, i_ph: float, t_wait: float,
                   temperature_K: float | None = None, v_fd: float | None = None) -> float:
    """Column signal (V) the FD adds while it waits ``t_wait``: leakage + parasitic light.

    ``v_fd``: the FD's bias while it stores (default the PD reset level); ``a_sf`` the SF
    gain there."""
    r = capacitances(design, which, a_sf, v_fd)
    i = leakage(design, temperature_K) + pls_current(design, i_ph, which)
    return a_sf * i * t_wait / r["c_fd_F"]
