"""The integrated dual pixel drawn from ``circuits.dual_pixel``: one PRIMARY above a row of N
SECONDARY cells, and the routing between them.

The floor plan (nm, origin lower left of ``DUALPIX``, N secondaries of pitch Ps under a
primary of pitch Pp = N Ps) is decided here and handed to the subpixel generator:

- each secondary's column line is a metal2 track at its right edge; the primary's is a
  metal4 track that runs straight down through the last secondary (which leaves metal4
  free), so ``col_p`` crosses the secondary row without a jog;
- the last secondary's column line runs straight up through the primary (a metal2 track
  the primary reserves); the others cannot - the primary's PD is above them - so each
  jogs (metal3, in a band the secondaries keep free at their top) to a metal4 track in
  the primary's transistor column, and jogs back at the primary's top (a band the primary
  keeps free) to continue on metal2 into the next dual pixel's secondary: every column
  line enters and leaves the cell at the same x, so dual pixels abut into arrays;
- the supplies (vdd, vpdr, vrst, vss) are vertical metal4 tracks over the primary's
  transistor column and the last secondary, tied by via stacks to the metal3 supply lines
  of both rows; the row signals stay on the rows' own lines (ec_p ... and ec_s ...).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .canvas import Canvas, box
from .pixel import SubpixelPlan, subpixel
from .primitives import pad_side
from .route import RouteError, stack_fits, track, via_on

SUPPLIES = ("vdd", "vpdr", "vrst", "vss")
CONTROLS = ("ec", "tg", "rst", "rs")


@dataclass(frozen=True)
class DualPlan:
    primary: SubpixelPlan
    secondary: SubpixelPlan
    n: int
    jog_low: tuple      # y (DUALPIX) of the lower jog of secondary column k < N-1
    jog_high: tuple     # y (DUALPIX) of the upper jog


def opening_box(lt, sub, pd) -> "box | None":
    """The square mask opening of the design's area centred on the PD (None: unmasked)."""
    if sub.mask_opening is None:
        return None
    side = lt.snap(math.sqrt(sub.mask_opening) * 1e9)
    g = lt.grid
    x0 = ((pd.cx - side // 2) // g) * g
    y0 = ((pd.cy - side // 2) // g) * g
    return box(x0, y0, x0 + side, y0 + side)


def plan(design, lt) -> DualPlan:
    n = design.secondary_per_pixel
    e = lt.snap(design.tech.rules.pd_to_cell_edge * 1e9)
    ps, pp = lt.snap(design.secondary.pitch * 1e9), lt.snap(design.primary.pitch * 1e9)
    pad3, pad4 = pad_side(lt, "metal3"), pad_side(lt, "metal4")
    s3, s4 = lt.space("metal3"), lt.space("metal4")
    # column tracks (metal4): each secondary's at its right edge; the primary's one track further
    # left, so that it runs straight down through the last secondary
    x_col_s = ps - s4 // 2 - pad4 // 2
    x_col_p = (n - 1) * ps + x_col_s - pad4 - s4
    # N - 1 metal3 jogs in a band under the primary's PD and in one at the primary's top
    yb = [s3 // 2 + pad3 // 2 + k * (pad3 + s3) for k in range(n - 1)]
    yt = [pp - s3 // 2 - pad3 // 2 - k * (pad3 + s3) for k in range(n - 1)]
    band_lo = (max(yb) + pad3 // 2 + s3) if yb else 0
    band_hi = (min(yt) - pad3 // 2 - s3) if yt else pp
    keep_p = tuple(b for b in ((0, band_lo), (band_hi, pp)) if b[1] > b[0])
    pds = _pd(lt, design.secondary, e, e)
    pdp = _pd(lt, design.primary, e, max(e, band_lo))
    sec = SubpixelPlan("secondary", ps, pds, opening_box(lt, design.secondary, pds), "metal4", x_col_s,
                       reserved=(("metal4", _track_box(lt, x_col_p - (n - 1) * ps, ps)),))
    pri = SubpixelPlan("primary", pp, pdp, opening_box(lt, design.primary, pdp), "metal4", x_col_p, keep_p,
                       (("metal4", _track_box(lt, (n - 1) * ps + x_col_s, pp)),))
    return DualPlan(pri, sec, n, tuple(ps + y for y in yb), tuple(ps + y for y in yt))


def _track_box(lt, x: int, h: int):
    w = pad_side(lt, "metal4")
    return box(x - w // 2, 0, x - w // 2 + w, h)


def _pd(lt, sub, ex, ey):
    return box(ex, ey, ex + lt.snap(sub.pd_width * 1e9), ey + lt.snap(sub.pd_height * 1e9))


def _free_track(cv: Canvas, lt, layer: str, y0: int, y1: int, xs, net: str, stacks=()) -> int:
    """The first x of ``xs`` where a full track and its via stacks ((y, bottom, top), ...) are free."""
    w = lt.width(layer)
    for x in xs:
        if not cv.free(layer, box(x - w // 2, y0, x - w // 2 + w, y1), net):
            continue
        if all(stack_fits(cv, lt, x, y, bot, top, net) for y, bot, top in stacks):
            return x
    raise RouteError(cv.name, net, f"no free {layer} track")


def _jog(cv: Canvas, lt, net: str, xa: int, xb: int, y: int) -> None:
    """metal4 track at xa -> metal3 at height y -> metal4 track at xb."""
    w = lt.width("metal3")
    seg = box(xa, y - w // 2, xb, y - w // 2 + w)
    if cv.fillers("metal3", seg, net) is None or not stack_fits(cv, lt, xa, y, "metal3", "metal4", net):
        raise RouteError(cv.name, net, f"the metal3 jog at y = {y / 1000:g} um is blocked")
    cv.add_filled("metal3", seg, net)
    via_on(cv, lt, net, xa, y, "metal3", "metal4")
    via_on(cv, lt, net, xb, y, "metal3", "metal4")


def dual_pixel(design, lt) -> tuple[dict, Canvas]:
    """The cells {name: Canvas} (PRIMARY, SECONDARY) and the DUALPIX canvas."""
    dp = plan(design, lt)
    pri = subpixel(design, lt, dp.primary)
    sec = subpixel(design, lt, dp.secondary)
    n, ps, pp = dp.n, dp.secondary.pitch, dp.primary.pitch
    top = Canvas("DUALPIX", lt)
    sec_nets = {**{c: f"{c}_s" for c in CONTROLS}, **{s: s for s in SUPPLIES}}
    for k in range(n):
        top.place(sec, k * ps, 0, {**sec_nets, "col": f"col_s{k}"}, name=f"xs{k}")
    top.place(pri, 0, ps, {**{c: f"{c}_p" for c in CONTROLS}, **{s: s for s in SUPPLIES}, "col": "col_p"},
              name="xp")
    height = ps + pp
    x_col_s, x_col_p = dp.secondary.col_x, dp.primary.col_x
    # the primary's column line straight down through the last secondary, the last secondary's
    # straight up through the primary (metal4)
    track(top, lt, "col_p", "metal4", x_col_p, 0, ps)
    track(top, lt, f"col_s{n - 1}", "metal4", (n - 1) * ps + x_col_s, ps, height)
    # the others: up to a jog under the primary's PD, a metal4 track over the primary's transistor
    # column, a jog back at the primary's top, and on up at their own x
    pitch4 = pad_side(lt, "metal4") + lt.space("metal4")
    xs = [x_col_p - pitch4 * (i + 1) for i in range(40)]
    for k in range(n - 1):
        net = f"col_s{k}"
        xk = k * ps + x_col_s
        ylo, yhi = dp.jog_low[k], dp.jog_high[k]
        x4 = _free_track(top, lt, "metal4", ylo, yhi, xs, net, ((ylo, "metal3", "metal4"), (yhi, "metal3", "metal4")))
        track(top, lt, net, "metal4", xk, ps, ylo)
        for y in (ylo, yhi):
            _jog(top, lt, net, xk, x4, y)
        track(top, lt, net, "metal4", x4, ylo, yhi)
        track(top, lt, net, "metal4", xk, yhi, height)
    # supplies: metal4 verticals over the primary's transistor column and the last secondary
    lines_p, lines_s = pri.ports["lines"], sec.ports["lines"]
    for net in SUPPLIES:
        stacks = ((lines_s[net], "metal3", "metal4"), (ps + lines_p[net], "metal3", "metal4"))
        x4 = _free_track(top, lt, "metal4", 0, height, xs, net, stacks)
        track(top, lt, net, "metal4", x4, 0, height)
        for y, bot, tp in stacks:
            via_on(top, lt, net, x4, y, bot, tp)
        top.label("metal4_label", x4, height // 2, net)
    # labels of the ports on the lines and tracks
    for c in CONTROLS:
        top.label("metal3_label", lt.width("metal3"), lines_s[c], f"{c}_s")
        top.label("metal3_label", lt.width("metal3"), ps + lines_p[c], f"{c}_p")
    top.label("metal4_label", x_col_p, ps // 2, "col_p")
    for k in range(n):
        top.label("metal4_label", k * ps + x_col_s, ps // 4, f"col_s{k}")
    top.add("boundary", box(0, 0, pp, height), "")
    top.ports = {"width": pp, "height": height, "col_p": ("metal4", x_col_p),
                 **{f"col_s{k}": ("metal4", k * ps + x_col_s) for k in range(n)},
                 "lines_p": lines_p, "lines_s": lines_s}
    return {"PRIMARY": pri, "SECONDARY": sec}, top

