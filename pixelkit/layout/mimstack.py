"""A column of MIM capacitors in a narrow cell, and the top-metal leads that take their plates to
metal4 landings the router can reach.

The MIM capacitors of option B sit between metal4 (their bottom plates) and the top metal (over
their top plates), so every connection leaves on the top metal, whose rules are wide (the 11 kA
MetalTop: 0.44 um wires, 0.46 um apart, 0.6 um from a wide plate). Rather than route the top
metal on a grid, each plate gets one lead, planned here:

- capacitors that share a node (the AFE's C11 - C13 share ``vm``) are stacked with that node on
  their top plates, joined plate to plate by top-metal bridges, and leave from the lowest plate
  straight down;
- each bottom plate's via sits on the right of its plate, except the middle capacitor's, on the
  left: the lowest capacitor's lead runs down on the right, the middle one's down a lane along
  the left edge (past the lowest, to a landing one landing pitch lower than the others, so its
  route arrives away from the lowest plate) and, mirrored, up the lane past the highest as far,
  with a twin of its via and pad (so the middle's bottom node faces the lowest and the highest
  bottom plates alike), the highest one's up on the right; the shared node's lead down from the
  lowest top plate has such a twin up from the highest;
- a lone capacitor (the op-amp's Cc) leaves both plates upwards.

A lead ends on a landing - a via down to a metal4 pad - outside the MIM's metal4 keep-out
(MIMTM.1: no metal4 within 1.2 um of a bottom plate). The landings are the router's terminals.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from .canvas import Box, Canvas, box
from .primitives import mim_cap, mim_extension, pad_side, square, top_metal_space



@dataclass
class Column:
    """Where a narrow cell's plates go (nm): the plate width, the x of a plate with its via on
    the right / on the left, the left lane."""
    plate_w: int
    x_right_via: int
    x_left_via: int
    lane: tuple            # (x0, x1) of the left lane


def column(lt, width: int) -> Column:
    """The widest plate a ``width`` nm cell holds with both kinds of via and the left lane."""
    e = lt.nm("mim_bottom.enclosure.mim_top")
    ext = mim_extension(lt)
    half_mim = lt.nm("mim_bottom.space") // 2
    wt = lt.width("metal5")
    lane0 = lt.snap_up(lt.space("metal5") / 2)
    lane = (lane0, lane0 + wt)
    x_r = lt.snap_up(max(half_mim + e, lane[1] + top_metal_space(lt)))
    x_l = half_mim + ext
    w = min(width - half_mim - ext - x_r, width - half_mim - e - x_l)
    return Column((w // lt.grid) * lt.grid, x_r, x_l, lane)


@dataclass
class Stack:
    """What a drawn stack leaves: the landings (net -> metal4 pads), its y extent, the plates."""
    landings: dict = field(default_factory=dict)
    y0: int = 0
    y1: int = 0
    plates: list = field(default_factory=list)


def landing_gap(lt) -> int:
    """From a bottom plate's edge to the centre of a landing beyond it: the MIM's metal4 keep-out,
    the landing's pad and a metal4 space (the router reaches the pad from outside the keep-out)."""
    return lt.snap_up(lt.nm("mim_bottom.space") + pad_side(lt, "metal4") + lt.space("metal4"))


def _landing(cv: Canvas, lt, st: Stack, net: str, x: int, y: int, terminal: bool = True) -> None:
    """A via from the top metal down to a metal4 pad at (x, y); ``terminal``: one the router reaches
    (else the twin of one, drawn for symmetry only)."""
    cv.add("via4", square(x, y, lt.cut("via4")), net)
    pad = cv.add("metal4", square(x, y, pad_side(lt, "metal4")), net)
    if terminal:
        st.landings.setdefault(net, []).append(pad)


def _lead(cv: Canvas, lt, st: Stack, net: str, x: int, y_from: int, y_land: int, terminal: bool = True) -> None:
    """A vertical top-metal lead centred on x from ``y_from`` to a landing at ``y_land``."""
    wt = lt.width("metal5")
    x = lt.snap(x)
    e = lt.cut("via4") // 2 + lt.nm("metal5.enclosure.via4")
    lo, hi = (y_land - e, y_from) if y_land < y_from else (y_from, y_land + e)
    cv.add("metal5", box(x - wt // 2, lo, x - wt // 2 + wt, hi), net)
    _landing(cv, lt, st, net, x, y_land, terminal)


def draw_stack(cv: Canvas, lt, col: Column, caps: list, y: int) -> Stack:
    """Capacitors ``caps`` = [(top net, bottom net, plate length)], lowest first, drawn from ``y``
    up. Two or three: their top nets the same (the shared node), landings below the stack (the
    shared node, the lowest and the middle capacitor) and above it (the highest). One: both its
    landings above it, its bottom plate at ``y`` (the caller keeps metal4 1.2 um off below)."""
    if not 1 <= len(caps) <= 3:
        raise ValueError("a stack holds one to three capacitors")
    e = lt.nm("mim_bottom.enclosure.mim_top")
    gap, pad4 = landing_gap(lt), pad_side(lt, "metal4")
    st = Stack(y0=y)
    sides = {1: ["right"], 2: ["right", "right"], 3: ["right", "left", "right"]}[len(caps)]
    # the middle's and the shared node's landings a landing pitch lower than the lowest's: their routes arrive
    # away from the lowest plate (the twins above rise as far)
    drop = pad4 + lt.space("metal4") if len(caps) == 3 else 0
    plate_y = y if len(caps) == 1 else y + gap + pad4 + drop       # the lowest bottom plate's edge
    made = []
    for (top, bottom, length), side in zip(caps, sides):
        x = col.x_left_via if side == "left" else col.x_right_via
        m = mim_cap(cv, lt, x, plate_y + e, col.plate_w, length, top, bottom, via_side=side)
        made.append((m, side, bottom))
        st.plates.append(m["plate"])
        plate_y = m["plate"].y1 + lt.nm("mim_bottom.space")
    y_up = made[-1][0]["plate"].y1 + gap
    st.y1 = y_up + pad4
    if len(caps) == 1:
        m, _side, bottom = made[0]
        _lead(cv, lt, st, caps[0][0], m["top"].cx, m["top"].y1, y_up)
        _lead(cv, lt, st, bottom, m["bottom"].cx, m["bottom"].cy, y_up)
        return st
    for (a, *_), (b, *_) in zip(made, made[1:]):          # the shared node, plate to plate
        cv.add("metal5", box(max(a["top"].x0, b["top"].x0), a["top"].y1, min(a["top"].x1, b["top"].x1),
                             b["top"].y0), caps[0][0])
    low, high = made[0][0], made[-1][0]
    y_down = low["plate"].y0 - gap
    _lead(cv, lt, st, caps[0][0], low["top"].cx, low["top"].y0, y_down - drop)
    # its twin up from the highest top plate, as far (no terminal): the shared node faces both ends alike
    _lead(cv, lt, st, caps[0][0], high["top"].cx, high["top"].y1, y_up + drop, terminal=False)
    for k, (m, side, bottom) in enumerate(made):
        pad = m["bottom"]
        if k == len(made) - 1:                                  # the highest: up on the right
            _lead(cv, lt, st, bottom, pad.cx, pad.cy, y_up)
        elif side == "left":                                    # the middle: down the left lane
            cv.add("metal5", box(col.lane[0], pad.y0, pad.x1, pad.y1), bottom)   # as tall as the pad: no notch
            _lead(cv, lt, st, bottom, (col.lane[0] + col.lane[1]) // 2, pad.cy, y_down - drop)
            # and mirrored up the same lane past the highest plate, as far beyond it as the lead reaches
            # below the lowest: the middle's bottom node then faces the lowest and the highest bottom
            # plates alike (the AFE's op-amp input x between c and in: docs/revisions.md)
            wt = lt.width("metal5")
            reach = lt.cut("via4") // 2 + lt.nm("metal5.enclosure.via4")
            top_end = made[-1][0]["plate"].y1 + (low["plate"].y0 - (y_down - drop - reach))
            cv.add("metal5", box(col.lane[0], pad.cy, col.lane[0] + wt, top_end), bottom)
            _landing(cv, lt, st, bottom, (col.lane[0] + col.lane[1]) // 2, top_end - reach, terminal=False)
            st.y1 = max(st.y1, top_end)
        else:                                                   # the lowest: down on the right
            _lead(cv, lt, st, bottom, pad.cx, pad.cy, y_down)
    return st


__all__ = ["Column", "Stack", "column", "draw_stack", "landing_gap"]
