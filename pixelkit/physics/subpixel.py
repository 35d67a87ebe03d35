"""Analytic figures of a design's primary and secondary subpixels.

The photodiode alone gives the thesis's [Thesis2019] C_jdep, conversion gain and full well
(table 3.2, eq. 3.10 - 3.13). The in-pixel PD *node* adds what the netlist hangs
on it: the EC and TG source diffusions (junction C with the technology's MOS
parameters) and their gate overlaps; this is what a SPICE discharge sees. What
the column sees (charge sharing with FD, the SF gain) is ``fd.response``.
"""
from __future__ import annotations

from . import conversion
from .dark import dark_current
from .fd import response
from .nodes import pd_node  # noqa: F401 (callers import the PD node from here)

SUBPIXELS = ("primary", "secondary")


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


def model_table(design, a_sf: float, sf_models: dict) -> dict:
    """The figures ``pixelkit models`` prints; ratios as eq. 3.10 and 3.13 define them.

    Besides the thesis's table at its 2.5 V, each subpixel gets ``at_reset``: the
    PD-referred and output-referred conversion gain side by side at the design's own
    PD reset level (``fd.response``). ``a_sf``: the SF gain; ``pixelkit.api.models`` takes
    it from a SPICE operating point of the SF and its column load (``camera.spicenoise.sf_gain``):
    the models stay importable and testable without the simulator above them; ``sf_models`` the
    follower's EKV parameters (``techfit.ekv.models_for``), for the switches' body factor (``fd.transfer``).
    """
    p, s = figures(design, "primary"), figures(design, "secondary")
    p["at_reset"], s["at_reset"] = (response(design, w, a_sf, sf_models) for w in SUBPIXELS)
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
