"""The pinned photodiode and its transfer gate in SPICE, from elements ngspice runs (a capacitor, a
current source, a voltage-controlled current source and behavioural B sources), and the floating
diffusion's own junction. The closed forms they implement, and are tested against, are
``physics.ppd``'s.

Nodes (inside the pixel's subcircuit):

- ``q``: the stored electrons as a voltage, ``V(q) = -Q / C_PPD`` on the capacitor ``Cppd`` (0 when
  empty, negative as electrons arrive). Every current into or out of the PPD is a current into
  ``q``, so the charge is conserved by construction: what ``Btr`` takes from the PPD it gives FD.

The PPD's quasi-Fermi potential V_F is not a node: it is ``physics.ppd.Ppd.potential`` of the charge
(a B voltage source for it made every transient crawl: V_F runs to +infinity as the well empties, and
ngspice cut its steps to ns to follow it).

Elements:

- ``Cppd q 0 C_PPD``
- ``Gph q 0 <light> 0 g``: the photocurrent, ``LIGHT_SCALE`` A per volt of the light port (the
  benches drive it in nA);
- ``Igen q 0 I_gen``: generation dark current (TG edge, isolation);
- ``Bdif 0 q``: the PPD's diode to the substrate, ``I_dif (exp(-V_F/U_T) - 1)``: the bulk diffusion
  dark current in reverse bias, the overflow (equilibrium full well) in forward bias;
- ``Btr fd q``: the thermionic-emission transfer over the TG barrier, forward minus reverse,
  ``I_spec [ln(1 + exp((phi_B - V_F)/U_T)) - ln(1 + exp((phi_B - V_FD)/U_T))]``: exponential in the
  barrier (thermionic emission), linear in the overdrive once the barrier is gone (a drift-limited
  transfer, time constant C_PPD U_T / I_spec, a fraction of a ns: the barrier, not this regime, sets
  the lag; a MOSFET's square law there made a dumped over-exposed well a ps-stiff system).

U_T and every current are evaluated at the deck's temperature when the deck is written (the kit
writes one deck per condition), so ngspice applies no temperature law of its own to them.
"""
from __future__ import annotations

from types import SimpleNamespace

from ..physics.dark import mos_junction_scale
from ..physics.geometry import diffusion
from ..spice.netlist import Behavioral, Element, fmt
from .devices import FC, sidewall_fc

#: A (photocurrent) per V on a pixel's light port: the benches drive the port in nA.
LIGHT_SCALE = 1e-9
#: The light port the kit adds to every pixel cell (a name a designer's subcircuit does not use).
LIGHT_PORT = "pklight"


def _x(q: str, ut: float) -> str:
    """Q / Q_T as an expression: -V(q) / U_T."""
    return f"(-V({q})/{fmt(ut)})"


def ppd_elements(ppd, q: str = "q", fd: str = "fd", tg: str = "tg", light: str = LIGHT_PORT,
                 fraction: float = 1.0) -> tuple:
    """The PPD's elements (module docstring) for the ``physics.ppd.Ppd`` ``ppd``."""
    ut, vpu = ppd.ut, ppd.v_pin / ppd.ut
    x = _x(q, ppd.ut)
    ch = ppd.channel
    a = ch.phi ** 0.5 + ch.gamma / 2
    vtg = f"V({tg})"
    # the barrier: the EKV pinch-off potential of the TG channel minus the edge barrier
    phi = (f"({vtg}-{fmt(ch.vt0)}-{fmt(ch.gamma)}*(sqrt(max({vtg}-{fmt(ch.vt0)}+{fmt(a * a)},0))-{fmt(a)})"
           f"-{fmt(ppd.barrier)})")
    i_s = ch.i_spec_on(ppd.temperature)
    # exp((phi - V_F) / U_T) = exp((phi - V_pin) / U_T) (exp(Q / Q_T) - 1): no V_F node needed
    # (an over-emptied well, Q < 0 by a numerical overshoot, pulls electrons back: the max keeps the log defined)
    fwd = f"ln(max(1+exp(({phi}-{fmt(ppd.v_pin)})/{fmt(ut)})*(exp({x})-1),1e-3))"
    rev = f"ln(1+exp(({phi}-V({fd}))/{fmt(ut)}))"
    out = [Element("Cppd", (q, "0"), ppd.c),
           Element("Gph", (q, "0", light, "0"), LIGHT_SCALE * fraction),
           Element("Igen", (q, "0"), ppd.i_gen),
           Element("Bdif", ("0", q), Behavioral("I", f"{fmt(ppd.i_dif)}*(exp({x}-{fmt(vpu)})-{fmt(2.718281828459045 ** -vpu)}-1)")),
           Element("Btr", (fd, q), Behavioral("I", f"{fmt(i_s)}*({fwd}-{rev})"))]
    return tuple(out)


def fd_junction(tech, w: float, temperature_K: float, node: str = "fd", tag: str = "fd") -> tuple[tuple, tuple]:
    """(elements, subcircuit-local model cards) of one n+ diffusion of width ``w`` on ``node`` (the TG
    drain, which the behavioural transfer gate does not draw as a MOSFET): bottom and field sidewall,
    and the gate-edge sidewall, with the technology's MOS junction parameters; saturation currents by
    BSIM4's junction law at ``temperature_K`` (``physics.dark.mos_junction_scale``), so its leakage
    is the one SPICE gives the other diffusions on FD."""
    mos = tech.mos
    a, p = diffusion(w, mos.diff_ext)
    k = mos_junction_scale(tech, temperature_K)
    t_c = temperature_K - 273.15
    # FCS as devices.sidewall_fc sets it for the photodiode: a forward-biased FD (an over-exposed pixel
    # dumping its charge) must not see the sidewall charge jump (ngspice then stops: timestep too small)
    fcs = sidewall_fc(SimpleNamespace(pb=mos.pb, mj=mos.mj, pbsw=mos.pbsw, mjsw=mos.mjsw))
    body = (f"dj_{tag}", "d", (("level", 1), ("is", mos.js * k), ("jsw", mos.jsw * k), ("n", mos.njs),
                               ("cjo", mos.cj), ("m", mos.mj), ("vj", mos.pb), ("cjp", mos.cjsw),
                               ("mjsw", mos.mjsw), ("php", mos.pbsw), ("fc", FC), ("fcs", fcs), ("tnom", t_c)))
    # the gate edge alone: its bottom terms equal to its sidewall's (cjo = 0), so the two charges agree
    edge = (f"djg_{tag}", "d", (("level", 1), ("is", 1e-30), ("n", 1.0), ("cjo", 0.0), ("m", mos.mjswg),
                                ("vj", mos.pbswg), ("cjp", mos.cjswg), ("mjsw", mos.mjswg), ("php", mos.pbswg),
                                ("fc", FC), ("fcs", FC), ("tnom", t_c)))
    el = (Element(f"D{tag}", ("0", node), f"dj_{tag}", (("area", a), ("pj", p - w))),
          Element(f"D{tag}g", ("0", node), f"djg_{tag}", (("area", 1e-18), ("pj", w))))
    return el, (body, edge)
