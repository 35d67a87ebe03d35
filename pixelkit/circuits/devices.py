"""Device elements built from a technology: MOSFETs (with AD/AS/PD/PS), photodiodes, switches."""
from __future__ import annotations

from ..spice.netlist import Element, Model
from ..physics.geometry import diffusion


def gate_high(design) -> float:
    """The EC / TG / RST gate-high level: the supply (``pixel.gate_drive = "supply"``: at the condition's
    supply) or the boosted rail ``pixel.v_gate`` (regulated: the same at every condition)."""
    px = design.pixel
    return px.v_gate if px.gate_drive == "boosted" else design.tech.supply


def mosfet(name: str, d: str, g: str, s: str, b: str, w: float, l: float, tech, kind: str = "n") -> Element:
    """A MOSFET of the technology, with its source/drain junction geometry."""
    mos = tech.mos
    a, p = diffusion(w, mos.diff_ext)
    prefix = "X" if mos.kind == "subckt" else "M"
    model = mos.nmos if kind == "n" else mos.pmos
    return Element(f"{prefix}{name}", (d, g, s, b), model,
                   (("w", w), ("l", l), ("ad", a), ("as", a), ("pd", p), ("ps", p)))


def tgate(name: str, a: str, b: str, clk: str, clkb: str, w: float, l: float, tech, vdd: str = "vdd"):
    """A CMOS transmission gate: NMOS driven by ``clk``, PMOS by ``clkb``."""
    return (mosfet(f"{name}n", a, clk, b, "0", w, l, tech, "n"),
            mosfet(f"{name}p", a, clkb, b, vdd, 2 * w, l, tech, "p"))


def photodiode(name: str, node: str, area: float, perimeter: float, tech) -> Element:
    """The PD junction (anode = substrate) with its area and perimeter."""
    return Element(f"D{name}", ("0", node), tech.photodiode.spice_model,
                   (("area", area), ("pj", perimeter)))


def photodiode_model(tech, temperature_K: float | None = None) -> tuple:
    """The kit's own diode card for technologies whose PD junction it calibrates.

    One dark-current law for SPICE and the analytic model: the card's saturation
    currents are ``physics.dark.dark_scale`` (the doubling law) evaluated at the
    deck's temperature, with TNOM at that temperature, so ngspice applies none of
    its own IS(T) (XTI/EG) or CJ(T) scaling. A reverse-biased level-1 diode carries
    -IS (area) - JSW (perimeter): the analytic dark current exactly.
    """
    from ..physics.dark import dark_scale
    pd = tech.photodiode
    if not pd.builtin_model:
        return ()
    t = pd.t_ref if temperature_K is None else temperature_K
    k = dark_scale(t, pd)
    return (Model(pd.spice_model, "d", (
        ("level", 1), ("is", pd.dark_area * k), ("jsw", pd.dark_perimeter * k), ("n", 1.0),
        ("cjo", pd.cj), ("m", pd.mj), ("vj", pd.pb), ("cjp", pd.cjsw), ("mjsw", pd.mjsw),
        ("php", pd.pbsw), ("tnom", t - 273.15), ("fc", FC), ("fcs", sidewall_fc(pd)))),)


#: Where the bottom junction's depletion charge turns linear in forward bias (SPICE's default).
FC = 0.5


def sidewall_fc(pd) -> float:
    """The sidewall's FCS that keeps the junction's charge continuous in forward bias.

    Beyond ``FCS * PHP`` ngspice (39 and the versions since, ``dioload.c``) continues the
    sidewall charge from ``CJSW * F1``, where F1 = PB (1 - (1 - FC)^(1 - MJ)) / (1 - MJ) is
    the *bottom* junction's; the sidewall's own charge there is PHP (1 - (1 - FCS)^(1 - MJSW))
    / (1 - MJSW). With PB != PHP or MJ != MJSW the two differ, the charge jumps when an
    over-exposed PD forward-biases past that point (0.277 V here) and the run stops
    ("timestep too small"). This FCS makes them equal, so the charge is continuous whether
    ngspice uses F1 or the sidewall's own value (depletion capacitance unchanged in reverse
    bias, where the PD works)."""
    f1 = pd.pb * (1 - (1 - FC) ** (1 - pd.mj)) / (1 - pd.mj)
    x = 1 - f1 * (1 - pd.mjsw) / pd.pbsw
    if not 0 < x < 1:   # no sidewall FCS in (0, 1) matches: the default, as before
        return FC
    return float(1 - x ** (1 / (1 - pd.mjsw)))
