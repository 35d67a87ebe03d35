"""The integrated dual pixel: one primary and N secondary 5T subpixels side by side.

The two arrays have separate control inputs and output buses ([Thesis2019] section 3.2):
ports ``vdd vpdr vrst ec_p tg_p rst_p rs_p col_p ec_s tg_s rst_s rs_s col_s0 .. col_s{N-1}``,
parameters ``iph_p`` and ``iph_s0 ..``: one photocurrent per subpixel.
"""
from __future__ import annotations

from ..spice.netlist import Element, Param, Subckt
from .pixel5t import pixel5t, wiring


def ports(n_secondary: int) -> tuple:
    return ("vdd", "vpdr", "vrst", "ec_p", "tg_p", "rst_p", "rs_p", "col_p", "ec_s", "tg_s", "rst_s", "rs_s",
            *(f"col_s{k}" for k in range(n_secondary)))


def dual_pixel(design) -> tuple[Subckt, ...]:
    """Subcircuits: both subpixel kinds and the integrated ``dualpix`` cell."""
    n = design.secondary_per_pixel
    elems = [Element("Xp", ("vdd", "vpdr", "vrst", "ec_p", "tg_p", "rst_p", "rs_p", "col_p"), "pix5t_primary",
                     (("iph", Param("iph_p")),))]
    for k in range(n):
        elems.append(Element(f"Xs{k}", ("vdd", "vpdr", "vrst", "ec_s", "tg_s", "rst_s", "rs_s", f"col_s{k}"),
                             "pix5t_secondary", (("iph", Param(f"iph_s{k}")),)))
    elems += wiring(design, "dualpix")
    params = (("iph_p", 0.0), *((f"iph_s{k}", 0.0) for k in range(n)))
    return (pixel5t(design, "primary"), pixel5t(design, "secondary"),
            Subckt("dualpix", ports(n), tuple(elems), params))
