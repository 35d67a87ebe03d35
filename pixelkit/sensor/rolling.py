"""Closed-form rolling-shutter distortion of a moving rectangle ([Rychazhnikov2008a], [Rychazhnikov2008b]).

Units: rows and columns (dy = dx = 1) and line times (T_c = 1), so the scan speed
v_H = 1 and the object's speed is s = v / v_H (0 <= s < 1). H = n rows is the
accumulation window (T_acc = n T_c), h and l the object's height and width.

Derivation (the kit's; the image simulation of ``exposure`` is its check).
Row y integrates over [y, y + n]. An object edge-to-edge of height h moving
vertically at s covers row y during an interval of length h / s whose start
moves by 1/s per row, while the row's window moves by 1 per row: relative to the
window the coverage interval slides by |1/s - 1| = (1 - s)/s per row moving with
the scan ("down") and (1 + s)/s against it ("up"). A row's signal is the overlap
of a length-h/s interval and a length-n window, so along the image the signal is
a trapezoid whose two ramps each span min(h/s, n) of that slide and whose flat
part spans |n - h/s|. With k = 1 - s (down) or 1 + s (up), in rows:

    edge  = min(h, s H) / k
    flat  = |s H - h| / k
    total = (h + s H) / k       = h + s (H + h) / (1 - s)   (down)
                                = h + s (H - h) / (1 + s)   (up)

The regimes split on h versus s H (how far the object moves during one
accumulation), not on h versus H.

Horizontal motion at s: row y sees the object over [x0 + s y, x0 + s (y + n) + l],
so every row is a trapezoid of extent l + s H with ramps min(l, s H) and flat
|s H - l|, shifted by s columns per row: the rectangle becomes a parallelogram
whose vertical borders lean by atan(s) from the vertical (base angle atan(1/s)),
its horizontal borders shifted by s h, total width l + s (H + h).

The published forms (``published_*``) are kept to show where they fail.
"""
from __future__ import annotations

import math

from ..errors import ConfigError

DIRECTIONS = ("down", "up", "right")


def check(h: float, window: float, s: float, l: float | None = None) -> None:
    for name, value in (("h", h), ("window", window)):
        if not value > 0:
            raise ConfigError("rolling", name, value, "a size > 0 rows")
    if l is not None and not l > 0:
        raise ConfigError("rolling", "l", l, "a width > 0 columns")
    if not 0 < s < 1:
        raise ConfigError("rolling", "speed", s, "a fraction of the scan speed, 0 < speed < 1")


def vertical(h: float, window: float, s: float, direction: str) -> dict:
    """Image sizes (rows) of an object moving with ("down") or against ("up") a downward scan."""
    check(h, window, s)
    k = 1 - s if direction == "down" else 1 + s
    return {"edge_rows": min(h, s * window) / k, "flat_rows": abs(s * window - h) / k,
            "total_rows": (h + s * window) / k}


def horizontal(h: float, l: float, window: float, s: float) -> dict:
    """Row profile, skew and total width (columns) of an object moving sideways."""
    check(h, window, s, l)
    return {"edge_cols": min(l, s * window), "flat_cols": abs(s * window - l), "row_extent_cols": l + s * window,
            "shift_per_row": s, "border_shift_cols": s * h, "total_cols": l + s * (window + h),
            "base_angle_deg": math.degrees(math.atan2(1.0, s)), "total_rows": h}


def sizes(h: float, window: float, s: float, direction: str, l: float = 20.0) -> dict:
    if direction not in DIRECTIONS:
        raise ConfigError("rolling", "direction", direction, f"one of {', '.join(DIRECTIONS)}")
    return horizontal(h, l, window, s) if direction == "right" else vertical(h, window, s, direction)


def published_vertical(h: float, window: float, s: float, direction: str) -> dict:
    """[Rychazhnikov2008a] eq. 1 - 8 (edges, flat part) and [Rychazhnikov2008b]'s total sizes, as printed."""
    H = window
    k = 1 - s if direction == "down" else 1 + s
    edge = s * (h if H > h else H) / k
    if direction == "down":
        flat = s * abs(H - h) / k + h
    else:
        flat = s * abs(H - h) / k          # [Rychazhnikov2008a] eq. 6 / 8: no "+ h" for upward motion
    return {"edge_rows": edge, "flat_rows": flat, "total_rows": s * (H + h) / k + h}


def published_horizontal(h: float, l: float, window: float, s: float) -> dict:
    """[Rychazhnikov2008a] eq. 9 - 12 and the base angle alpha = atan(h / (L1 + L2))."""
    H = window
    edge = s * (h if H > h else H)
    return {"edge_cols": edge, "flat_cols": s * abs(H - h) + l, "border_shift_cols": s * H,
            "total_cols": s * (h + H) + l, "base_angle_deg": math.degrees(math.atan2(h, s * H))}
