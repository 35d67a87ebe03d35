"""The 5T subpixel drawn from its netlist (``circuits.pixel5t``): the photodiode and the EC, TG,
RST, SF and RS transistors with the W / L of the design, routed.

Floor plan of one subpixel (pitch x pitch, origin lower left), the same for the primary
and the secondary cell:

- the PD (n-well, ``pd_width`` x ``pd_height``) ``pd_to_cell_edge`` from the lower-left
  corner, its N+ contact near its right edge, the P+ substrate tap right of its lower
  corner, the photodiode marker over both;
- right of the PD, two vertical transistor strips: EC - TG - RST in series (vpdr | EC |
  pd | TG | fd | RST | vrst, gate pads on the right) and above it SF - RS (vdd | SF | sfo
  | RS | col, gate pads on the left, in the metal1 lane that carries fd up from the first
  strip to the SF gate);
- the row signals (ec, tg, rst, rs) and supplies (vdd, vpdr, vrst, vss) as full-width
  metal3 lines, each placed by the router next to its terminal, reached through metal2
  jogs; never over the light path (the PD of an unmasked subpixel, the mask opening of a
  masked one) and never in the bands the dual pixel reserves for its own routing;
- the column line as a vertical track (metal2 in the secondary, metal4 in the primary:
  the plan decides), reached from RS's source by a via stack;
- the light shield on the top metal over the whole cell except the mask opening (or the
  PD of an unmasked subpixel), with the opening marker.
"""
from __future__ import annotations

from dataclasses import dataclass

from .canvas import Box, Canvas, box
from .primitives import Mos, gate_contact_offset, mos_strip, pad_side, pd_contact_inset, photodiode, tap, tap_size
from .route import Lines, route_all, stub_to_track, track
from .rules import RuleError

#: The row lines of a subpixel, bottom terminal first (the router's order).
LINE_NETS = ("vss", "vpdr", "ec", "tg", "rst", "vrst", "vdd", "rs")
STRIP1 = ("ec", "tg", "rst")
STRIP2 = ("sf", "rs")
#: the first strip's chain: each device's lower terminal net (its upper one is the next device's)
CHAIN_BELOW = {"ec": "vpdr", "tg": "pd", "rst": "fd"}


def chain_nets(devices) -> list:
    """[sd0, g0, sd1, g1, ... sdN] of the first strip (``vpdr | EC | pd | TG | fd | RST | vrst``, or without
    EC for a 4T pixel: ``pd | TG | fd | RST | vrst``)."""
    out = []
    for d in devices:
        out += [CHAIN_BELOW[d], d]
    return out + ["vrst"]
METAL_UP = ("metal1", "metal2", "metal3", "metal4")


@dataclass(frozen=True)
class SubpixelPlan:
    """What the dual pixel decides for one subpixel kind (all nm)."""
    which: str               # "primary" | "secondary"
    pitch: int
    pd: Box
    opening: Box | None      # None: unmasked
    col_layer: str
    col_x: int
    keep_m3: tuple = ()      # y bands without lines (the dual pixel's jogs)
    reserved: tuple = ()     # (layer, Box): tracks left free for the dual pixel
    strip1: tuple = STRIP1   # the first strip's transistors (a 4T pixel: no EC)

    @property
    def name(self) -> str:
        return self.which.upper()


def device_sizes(design, lt, names) -> list[Mos]:
    """The transistors ``names`` of the design in nm; a size off the grid or under the rule is refused
    with its field."""
    dev = design.pixel.devices
    out = []
    for n in names:
        w = lt.size_nm(getattr(dev, f"{n}_w"), f"pixel.devices.{n}_w", f"{n.upper()} transistor", "active.width")
        l_ = lt.size_nm(getattr(dev, f"{n}_l"), f"pixel.devices.{n}_l", f"{n.upper()} transistor",
                        low=lt.snap_up(design.tech.mos.lmin * 1e9), low_rule="mos.lmin")
        out.append(Mos(n, w, l_))
    return out


def _fit_error(design, which: str, plan: SubpixelPlan, devs, what: str, need: int, room: int, axis: str):
    """The transistors overflow the cell: name the sizes that use the overflowing axis."""
    sub = getattr(design, which)
    # blame the PD when a PD of the technology's smallest side would leave the devices room
    spare = (plan.pd.w if axis == "x" else plan.pd.h) - round(design.tech.rules.min_pd_side * 1e9)
    if need <= room + spare:
        side = "width" if axis == "x" else "height"
        value = getattr(sub, f"pd_{side}")
        return RuleError("transistors_fit", f"{plan.name} cell",
                         f"{what} needs {need / 1000:g} um {'beside' if axis == 'x' else 'along'} the PD, the "
                         f"{plan.pitch / 1000:g} um cell leaves {room / 1000:g} um: pd_{side} at most "
                         f"{(value * 1e9 - (need - room)) / 1000:g} um", f"{which}.pd_{side}", value)
    if axis == "x":
        d = max(devs, key=lambda m: m.w)
        field, value = f"pixel.devices.{d.name}_w", getattr(design.pixel.devices, f"{d.name}_w")
        detail = (f"{what} needs {need / 1000:g} um beside the PD, the {plan.pitch / 1000:g} um cell has "
                  f"{room / 1000:g} um: {d.name}_w at most {(d.w - (need - room)) / 1000:g} um")
    else:
        names = ", ".join(f"{m.name}_l" for m in devs)
        field, value = f"pixel.devices.{devs[0].name}_l", getattr(design.pixel.devices, f"{devs[0].name}_l")
        detail = (f"{what} ({names}) need {need / 1000:g} um of height, the {plan.pitch / 1000:g} um cell has "
                  f"{room / 1000:g} um")
    return RuleError("transistors_fit", f"{plan.name} cell", detail, field, value)


def subpixel(design, lt, plan: SubpixelPlan, place_only: bool = False) -> Canvas:
    """The subpixel cell of ``plan`` (see the module docstring); ``place_only``: stop once the
    devices are placed and checked to fit (no routing: the quick check of every command)."""
    which = plan.which
    cv = Canvas(plan.name, lt)
    P = plan.pitch
    pd = plan.pd
    cv.add("boundary", box(0, 0, P, P), "")
    s1 = pad_side(lt, "metal1")
    m1s = lt.space("metal1")
    d1, d2 = device_sizes(design, lt, plan.strip1), device_sizes(design, lt, STRIP2)
    nets1 = chain_nets(plan.strip1)
    on1 = [True] * (len(d1) + 1)
    nets2 = ["vdd", "fd", "sfo", "rs", "col"]
    # heights: a scratch drawing of each strip at y = 0
    scratch = Canvas("scratch", lt)
    h1 = mos_strip(scratch, lt, "n", 0, 0, d1, nets1, on1, "right")
    h2 = mos_strip(scratch, lt, "n", 0, 0, d2, nets2, [True, False, True], "left")
    off_pd = dict(h1.sd)["pd"].cy
    gap12 = lt.space("active")
    enc_np = lt.nm("nplus.enclosure.active")
    side, iside = tap_size(lt, "p")
    inset = pd_contact_inset(lt)
    below = max(iside // 2 + enc_np + side // 2, side + enc_np + lt.nm("nplus.space_to.active"),
                side + lt.space("active"))      # strip start above the substrate tap's COMP bottom
    # the strips as high as the PD's contact row and the cell allow (short jogs to the lines),
    # and no lower than the substrate tap under them
    y_hi = min(pd.y1 - inset - off_pd, P - lt.space("nplus") // 2 - enc_np - h1.comp.h - gap12 - h2.comp.h)
    y_lo = max(pd.y0 + below, pd.y0 + inset - off_pd)
    if y_hi < y_lo:
        raise _fit_error(design, which, plan, d1 + d2, "the transistors", h1.comp.h + gap12 + h2.comp.h + below +
                         lt.space("nplus") // 2 + enc_np, P - pd.y0, "y")
    y1 = _strip_row(lt, plan, h1, h2, gap12, below, side, y_lo, y_hi)
    s1 = pad_side(lt, "metal1")
    m1s = lt.space("metal1")
    lane0 = pd.x1                                   # the fd lane (metal1) starts at the PD edge
    lane_w = lt.width("metal1")
    x1 = lane0 + lane_w + m1s + (s1 - lt.cut("contact") - 2 * lt.nm("contact.enclosure.active")) // 2
    x1 = lt.snap_up(max(x1, pd.x1 + lt.nm("nwell.space_to.ncomp")))
    # the PD's N+ contact deep enough inside that its implant keeps its space to the strip's
    n_iside = tap_size(lt, "n")[1]
    inset = lt.snap_up(max(inset, pd.x1 - (x1 - lt.nm("nplus.enclosure.gate") - lt.space("nplus")) + n_iside // 2))
    lane2 = s1 + lt.space("metal2")                 # second lane of the first strip's gate vias
    a = mos_strip(cv, lt, "n", x1, y1, d1, nets1, on1, "right", stagger=lane2)
    # the substrate tap under the first strip: at its right end when the cell has room there
    # (its long jog to the lines then clears the strip's own), else at its left end
    ty = y1 - below + side // 2
    tx = a.extent.x1 + pad_side(lt, "metal2") + lt.space("metal2") + side // 2
    limit = plan.col_x - pad_side(lt, plan.col_layer) // 2 - lt.space("metal2") - pad_side(lt, "metal2")
    if tx + iside // 2 > limit or tx + s1 // 2 + m1s + s1 > limit:
        tx = pd.x1 + lt.nm("nwell.space_to.pcomp") + side // 2
    sub_comp, sub_pad = tap(cv, lt, "p", tx, ty, "vss")
    cx0 = gate_contact_offset(lt, d2, [True, False, True])
    cut = lt.cut("contact")
    x2 = lane0 + (s1 - cut) // 2 + cut + cx0     # its gate pads in the fd lane
    y2 = a.comp.y1 + gap12
    b = mos_strip(cv, lt, "n", x2, y2, d2, nets2, [True, False, True], "left")
    # fit: the strips inside the cell, clear of the column track
    right = max(a.extent.x1, b.extent.x1)
    room_x = P - lt.space("metal1") // 2 - lane0
    if right - lane0 > room_x:
        worst = d1 if a.extent.x1 >= b.extent.x1 else d2
        raise _fit_error(design, which, plan, worst, "the transistor strip", right - lane0, room_x, "x")
    if place_only:
        return cv
    # photodiode, its contact in line with the pd source of the first strip
    pd_pad = dict(a.sd)["pd"]
    cy = pd_pad.cy
    pdm = photodiode(cv, lt, pd, (pd.x1 - inset, cy), "pd", sub_comp)
    cv.add("metal1", box(pdm.x0, pd_pad.y0, pd_pad.x1, pd_pad.y1), "pd")
    # fd: first strip's fd source -> the lane -> the SF gate pad
    fd_pad, sf_gate = dict(a.sd)["fd"], b.gates[0][1]
    cv.add("metal1", box(sf_gate.x0, fd_pad.y0, fd_pad.x1, fd_pad.y1), "fd")   # fd source -> the lane
    cv.add("metal1", box(sf_gate.x0, fd_pad.y0, sf_gate.x0 + lane_w, sf_gate.y1), "fd")
    # light path: the router keeps every metal off it
    light = plan.opening if plan.opening is not None else pd
    cv.block(METAL_UP, light)
    for layer, rb in plan.reserved:
        cv.block([layer], rb, "#reserved")
    # column track and its connection from RS's source
    col_pad = dict(b.sd)["col"]
    stub_to_track(cv, lt, "col", col_pad, plan.col_x, plan.col_layer)
    track(cv, lt, "col", plan.col_layer, plan.col_x, 0, P)
    cv.label(f"{plan.col_layer}_label", plan.col_x, P // 2, "col")
    # row lines
    half = lt.space("metal3") // 2
    bands = _bands(half, P - half, plan)
    lines = Lines("metal3", 0, P, bands)
    terminals = {"vss": sub_pad, **{n: p for n, p in a.sd if n in LINE_NETS}, **{n: p for n, p in b.sd if n in LINE_NETS},
                 **{n: p for n, p in a.gates}, "rs": b.gates[1][1]}
    order = sorted((n for n in LINE_NETS if n != "vss" and n in terminals), key=lambda n: terminals[n].cy) + ["vss"]
    route_all(cv, lt, lines, terminals, order)
    cv.ports = {"lines": dict(lines.y), "col": (plan.col_layer, plan.col_x)}
    # light shield and the opening marker
    _shield(cv, lt, P, light)
    if plan.opening is not None:
        cv.add("opening", plan.opening, "")
    return cv


def _strip_row(lt, plan: SubpixelPlan, h1, h2, gap12: int, below: int, side: int, y_lo: int, y_hi: int) -> int:
    """The first strip's start: as high as allowed, lowered until every terminal that needs a
    line has a row a line may take (not across the light path or a kept band)."""
    w3, s3 = lt.width("metal3"), lt.space("metal3")
    light = plan.opening if plan.opening is not None else plan.pd
    bad = [(light.y0 - s3 - w3 // 2, light.y1 + s3 + w3 // 2)]
    bad += [(k0 - w3 // 2, k1 + w3 // 2) for k0, k1 in plan.keep_m3]
    rows = [p.cy for n, p in h1.sd if n in LINE_NETS] + [p.cy for n, p in h1.gates]
    rows += [h1.comp.h + gap12 + p.cy for n, p in h2.sd if n in LINE_NETS] + [h1.comp.h + gap12 + h2.gates[1][1].cy]
    rows.append(side // 2 - below)
    best = None
    y = (y_hi // lt.grid) * lt.grid
    while y >= y_lo:
        n_bad = sum(1 for r in rows if any(b0 < y + r < b1 for b0, b1 in bad))
        if best is None or n_bad < best[0]:
            best = (n_bad, y)
        if n_bad == 0:
            break
        y -= 50
    return best[1]


def _bands(lo: int, hi: int, plan: SubpixelPlan) -> list:
    """y ranges a full-width line may use: the cell minus the light path's rows and the keep bands."""
    cut = [(plan.opening.y0, plan.opening.y1) if plan.opening is not None else (plan.pd.y0, plan.pd.y1)]
    cut += list(plan.keep_m3)
    bands = [(lo, hi)]
    for c0, c1 in cut:
        nxt = []
        for b0, b1 in bands:
            if c1 <= b0 or c0 >= b1:
                nxt.append((b0, b1))
                continue
            if c0 > b0:
                nxt.append((b0, c0))
            if c1 < b1:
                nxt.append((c1, b1))
        bands = nxt
    return bands


def _shield(cv: Canvas, lt, P: int, hole: Box) -> None:
    """The top-metal shield over the cell but ``hole``, as four rectangles."""
    for b in (box(0, 0, P, hole.y0), box(0, hole.y1, P, P), box(0, hole.y0, hole.x0, hole.y1),
              box(hole.x1, hole.y0, P, hole.y1)):
        if b.w > 0 and b.h > 0:
            cv.add("shield", b, "shield")
