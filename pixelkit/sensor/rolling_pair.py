"""One object seen by two synchronous sensors scanning down and up: sizes, model and compensation.

What ``pixelkit sensor rolling`` prints: the down-scanning sensor's image against
the closed forms (the kit's and the documents'), and the compensation from the
pair of images.
"""
from __future__ import annotations

import math

import numpy as np

from . import compensation, rolling
from .rolling_image import measure_horizontal, measure_vertical, row_edges, simulate
from .profile import trapezoid


def _finite_or_none(x: float):
    """The article's quadratic may have no root in (0, L'): JSON null then."""
    return None if math.isnan(x) else x


def _sideways(h, window, s, l, per_cell, a, b) -> tuple[dict, dict]:
    """Lean, edges and total width; the row-averaged pair against the global-shutter image."""
    ma, mb = measure_horizontal(a), measure_horizontal(b)
    model = rolling.horizontal(h, l, window, s)
    gs = simulate(h, window, s, "right", "down", l, per_cell, shape=a.image.shape, mode="global")
    comp = compensation.average_rows(a.image, b.image)
    ec, eg = row_edges(comp), row_edges(gs.image)
    rows = np.intersect1d(ec["rows"], eg["rows"])
    sel_c, sel_g = np.isin(ec["rows"], rows), np.isin(eg["rows"], rows)
    lean = float(np.polyfit(ec["rows"], ec["half_left"], 1)[0]) if ec["rows"].size > 1 else 0.0
    numbers = dict(
        model_total_rows=model["total_rows"], image_total_rows=ma["total_rows"],
        model_edge_rows=0.0, image_edge_rows=trapezoid(a.image.max(axis=1))["edge"],
        model_total_cols=model["total_cols"], image_total_cols=ma["total_cols"],
        model_edge_cols=model["edge_cols"], image_edge_cols=ma["edge_cols"],
        model_shift_per_row=s, image_shift_per_row=ma["shift_per_row"],
        image_shift_per_row_up_scan=mb["shift_per_row"],
        model_base_angle_deg=model["base_angle_deg"], image_base_angle_deg=ma["base_angle_deg"],
        published=rolling.published_horizontal(h, l, window, s),
        compensated_h_rows=trapezoid(comp.max(axis=1))["fwhm"],
        compensated_speed=0.5 * (ma["shift_per_row"] - mb["shift_per_row"]),
        compensated_shift_per_row=lean,
        compensated_vs_global_max_edge_cols=float(max(
            np.abs(ec["left"][sel_c] - eg["left"][sel_g]).max(),
            np.abs(ec["right"][sel_c] - eg["right"][sel_g]).max())),
    )
    return numbers, {"down_scan": a.image, "up_scan": b.image, "compensated": comp, "global": gs.image}


def _vertical(h, window, s, direction, a, b) -> tuple[dict, dict]:
    """Sizes against the closed forms; height and speed from the two heights, rows rescaled."""
    ma, mb = measure_vertical(a), measure_vertical(b)
    model = rolling.vertical(h, window, s, direction)
    other = "up" if direction == "down" else "down"
    c = compensation.vertical(ma["total_rows"], mb["total_rows"], window)
    centre_a = 0.5 * (ma["top"] + ma["bottom"])
    comp = compensation.rescale_rows(a.image, centre_a, c["h_rows"] / ma["total_rows"])
    numbers = dict(
        model_total_rows=model["total_rows"], image_total_rows=ma["total_rows"],
        model_edge_rows=model["edge_rows"], image_edge_rows=ma["edge_rows"],
        model_flat_rows=model["flat_rows"], image_flat_rows=ma["flat_rows"],
        image_support_rows=ma["support_rows"],
        model_total_rows_up_scan=rolling.vertical(h, window, s, other)["total_rows"],
        image_total_rows_up_scan=mb["total_rows"],
        published=rolling.published_vertical(h, window, s, direction),
        published_up_scan_total_rows=rolling.published_vertical(h, window, s, other)["total_rows"],
        compensated_h_rows=c["h_rows"], compensated_speed=c["speed"],
        published_quadratic_h_rows=_finite_or_none(
            compensation.published_height(c["compressed_rows"], c["stretched_rows"], window)),
        image_centre_row=centre_a, true_centre_row=a.true_centre_row(),
    )
    return numbers, {"down_scan": a.image, "up_scan": b.image, "compensated": comp}


def study(h: float, window: float, s: float, direction: str, l: float = 8.0, per_cell: int = 16) -> dict:
    """Simulate both sensors, measure, compensate; numbers plus the frames for pictures."""
    rolling.sizes(h, window, s, direction, l)            # validates the inputs
    a = simulate(h, window, s, direction, "down", l, per_cell)
    b = simulate(h, window, s, direction, "up", l, per_cell, shape=a.image.shape)
    numbers, frames = (_sideways(h, window, s, l, per_cell, a, b) if direction == "right"
                       else _vertical(h, window, s, direction, a, b))
    out = {"direction": direction, "h_rows": h, "window_rows": window, "speed": s, "l_cols": l, **numbers}
    return {"numbers": out, "frames": frames}
