"""Arrays of integrated dual pixels (2 x 2 = 4 primary + 12 secondary, up to the chip's 27 x 50).

``pixel_array(design, rows, cols)`` is a subcircuit ``pixarray_RxC`` with ports

    vdd vpdr vrst ec_p tg_p ec_s tg_s            global (EC / TG: global shutter)
    rs_p_r rst_p_r rs_s_r rst_s_r  (each row r)  row select and FD reset per row
    col_p_c (each primary column), col_s_j (each secondary column, j = N c + k)

and one photocurrent parameter per subpixel: ``iph_p_r_c`` and ``iph_s_r_j``.
"""
from __future__ import annotations

from ..spice.netlist import Element, Param, Subckt


def array_ports(design, rows: int, cols: int) -> tuple:
    n = design.secondary_per_pixel
    rows_ = [f"{k}_{r}" for r in range(rows) for k in ("rs_p", "rst_p", "rs_s", "rst_s")]
    return ("vdd", "vpdr", "vrst", "ec_p", "tg_p", "ec_s", "tg_s", *rows_,
            *(f"col_p_{c}" for c in range(cols)), *(f"col_s_{j}" for j in range(n * cols)))


def pixel_array(design, rows: int, cols: int) -> Subckt:
    if rows < 1 or cols < 1:
        raise ValueError("an array needs at least one row and one column")
    n = design.secondary_per_pixel
    elems, params = [], []
    for r in range(rows):
        for c in range(cols):
            sec_cols = [f"col_s_{n * c + k}" for k in range(n)]
            p = [("iph_p", Param(f"iph_p_{r}_{c}"))]
            p += [(f"iph_s{k}", Param(f"iph_s_{r}_{n * c + k}")) for k in range(n)]
            elems.append(Element(f"Xpix_{r}_{c}", ("vdd", "vpdr", "vrst", "ec_p", "tg_p", f"rst_p_{r}",
                                                   f"rs_p_{r}", f"col_p_{c}", "ec_s", "tg_s", f"rst_s_{r}",
                                                   f"rs_s_{r}", *sec_cols), "dualpix", tuple(p)))
            params.append((f"iph_p_{r}_{c}", 0.0))
            params += [(f"iph_s_{r}_{n * c + k}", 0.0) for k in range(n)]
    return Subckt(f"pixarray_{rows}x{cols}", array_ports(design, rows, cols), tuple(elems), tuple(params))
