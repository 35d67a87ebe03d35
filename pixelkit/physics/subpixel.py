"""Analytic figures of a design's primary and secondary subpixels.

The photodiode alone gives the thesis's C_jdep, conversion gain and full well
(table 3.2, eq. 3.10 - 3.13). The in-pixel PD *node* adds what the netlist hangs
on it: the EC and TG source diffusions (junction C with the technology's MOS
parameters) and their gate overlaps; this is what a SPICE discharge sees. What
the column sees (charge sharing with FD, the SF gain) is ``fd.response``.
"""
from __future__ import annotations

from ..physics import conversion
from .dark import dark_current
from .fd import response, switch_side
from .junction import Junction, Node

SUBPIXELS = ("primary", "secondary")


def pd_node(design, which: str, parasitics: bool = False) -> Node:
    """C(V) of the photodiode of ``which`` subpixel, optionally with its switch parasitics
    (EC and TG source diffusions and overlaps, gates at 0 V, overlaps at the PD reset level)."""
    sub = getattr(design, which)
    tech = design.tech
    terms = [(sub.area, sub.perimeter, Junction.of(tech.photodiode))]
    c_fixed = 0.0
    if parasitics:
        dev = design.pixel.devices
        for w in (dev.ec_w, dev.tg_w):
            t, c = switch_side(w, tech, -design.pixel.v_pd_reset)
            terms += t
            c_fixed += c
    return Node(tuple(terms), c_fixed)


def figures(design, which: str) -> dict:
    sub = getattr(design, which)
    v_r = design.tech.photodiode.reset_bias
    node = pd_node(design, which)
    c = float(node.capacitance(v_r))
    return {
        "c_jdep_F": c,
        "cg_V_per_e": conversion.conversion_gain(c),
        "fwc_e": conversion.full_well(design.pixel.swing, c),
        "fwc_cv_e": conversion.full_well_cv(node, v_r, design.pixel.swing),
        "area_m2": sub.area,
        "perimeter_m": sub.perimeter,
        "photoactive_area_m2": sub.photoactive_area,
        "c_node_F": float(pd_node(design, which, parasitics=True).capacitance(v_r)),
        "dark_current_A": dark_current(sub.area, sub.perimeter, design.temperature, design.tech.photodiode),
    }


def model_table(design, a_sf: float | None = None) -> dict:
    """The figures ``pixelkit models`` prints; ratios as eq. 3.10 and 3.13 define them.

    Besides the thesis's table at its 2.5 V, each subpixel gets ``at_reset``: the
    PD-referred and output-referred conversion gain side by side at the design's own
    PD reset level (``fd.response``). ``a_sf``: the SF gain, default from a SPICE
    operating point of the SF and its column load (``camera.spicenoise.sf_gain``).
    """
    if a_sf is None:
        from ..camera.spicenoise import sf_gain
        a_sf = sf_gain(design)
    p, s = figures(design, "primary"), figures(design, "secondary")
    p["at_reset"], s["at_reset"] = (response(design, w, a_sf) for w in SUBPIXELS)
    return {
        "design": design.name,
        "technology": design.tech.name,
        "reset_bias_V": design.tech.photodiode.reset_bias,
        "primary": p,
        "secondary": s,
        "c_a": p["area_m2"] / s["area_m2"],
        "c_c": p["c_jdep_F"] / s["c_jdep_F"],
        "photoactive_ratio": p["photoactive_area_m2"] / s["photoactive_area_m2"],
    }
