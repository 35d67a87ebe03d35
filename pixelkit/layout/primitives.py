"""Device primitives every circuit reuses: MOSFET strips with contacts and implants, taps,
contacted pads and via stacks, the photodiode with its marker, the MIM capacitor.

Each draws on a :class:`~pixelkit.layout.canvas.Canvas` with every length taken from the
technology by rule name (``LayoutTech.nm``), and returns where its terminals are (metal1
pads, in nm), so that routing is a separate step. Conventions: a MOSFET strip runs
vertically (current along y, gates as horizontal poly); its COMP is aligned on one edge
(where the gate end caps are) and each gate's width is the drawn COMP width at that gate,
widening only for a contact, at least ``poly.space_to.active`` away from a narrower gate;
the gate pads sit on the other side.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from .canvas import Box, Canvas, box

METALS = ("metal1", "metal2", "metal3", "metal4", "metal5")
VIAS = {("metal1", "metal2"): "via1", ("metal2", "metal3"): "via2", ("metal3", "metal4"): "via3",
        ("metal4", "metal5"): "via4"}


def metal_index(layer: str) -> int:
    return METALS.index(layer)


def square(cx: int, cy: int, side: int) -> Box:
    h = side // 2
    return Box(cx - h, cy - h, cx - h + side, cy - h + side)


def pad_side(lt, metal: str) -> int:
    """Side of a square pad on ``metal`` that holds the vias below and above it and meets the
    layer's area rule."""
    key = ("pad_side", metal)
    if key not in lt.memo:
        lt.memo[key] = _pad_side(lt, metal)
    return lt.memo[key]


def _pad_side(lt, metal: str) -> int:
    i = metal_index(metal)
    sides = [lt.snap_up(math.sqrt(lt.area(f"{metal}.area")))] if lt.has(f"{metal}.area") else []
    if i == 0:
        sides.append(lt.cut("contact") + 2 * lt.enclosure("metal1", "contact"))
    if i > 0:
        sides.append(lt.pad(metal, VIAS[METALS[i - 1], metal]))
    if i < len(METALS) - 1 and lt.tech.layout.layers.get(VIAS[metal, METALS[i + 1]]) is not None:
        sides.append(lt.pad(metal, VIAS[metal, METALS[i + 1]]))
    return max(sides)


def stack_shapes(lt, x: int, y: int, bottom: str, top: str) -> list[tuple[str, Box]]:
    """Pads and cuts from ``bottom`` metal up to ``top`` metal, centred on (x, y)."""
    out = []
    lo, hi = metal_index(bottom), metal_index(top)
    for i in range(lo, hi + 1):
        out.append((METALS[i], square(x, y, pad_side(lt, METALS[i]))))
        if i < hi:
            via = VIAS[METALS[i], METALS[i + 1]]
            out.append((via, square(x, y, lt.cut(via))))
    return out


def contact_pad(cv: Canvas, lt, cx: int, cy: int, base: str, net: str) -> Box:
    """A contact on ``base`` (active or poly, drawn by the caller) with its metal1 pad."""
    cv.add("contact", square(cx, cy, lt.cut("contact")), net)
    return cv.add("metal1", square(cx, cy, pad_side(lt, "metal1")), net)


@dataclass
class Mos:
    """One transistor of a strip: name, width and length (nm), n or p."""
    name: str
    w: int
    l: int


@dataclass
class Strip:
    """Where a drawn strip's terminals are: ``sd[i]`` (net, metal1 pad or None), ``gates[i]``
    (net, metal1 pad), the strip's outline (COMP) and its implant box."""
    sd: list = field(default_factory=list)
    gates: list = field(default_factory=list)
    comp: Box = None
    implant: Box = None
    extent: Box = None


def fold(lt, w: int, wmax: int) -> tuple[int, int] | None:
    """(number of fingers, finger W in nm) splitting a ``w`` nm wide transistor into the fewest
    fingers of equal W at most ``wmax`` on the grid and at least the COMP width; None: none do."""
    n = max(1, -(-w // max(wmax, 1)))
    while n <= 64:
        if w % n == 0 and (w // n) % lt.grid == 0 and lt.width("active") <= w // n <= wmax:
            return n, w // n
        n += 1
    return None


def finger_nets(a: str, g: str, b: str, n: int, start: str) -> list[str]:
    """The strip nets [sd0, g, sd1, g, ...] of ``n`` fingers between ``a`` and ``b`` (gate ``g``),
    source and drain alternating from ``start``."""
    nets, cur = [start], start
    for _ in range(n):
        cur = b if cur == a else a
        nets += [g, cur]
    return nets


def _region_lengths(lt, devs: list[Mos], contacted: list[bool], wc: int, pad_h: int, m1pad: int) -> list[int]:
    """Lengths (y) of the n+1 source/drain regions of a strip of ``devs``."""
    cut, enc = lt.cut("contact"), lt.nm("contact.enclosure.active")
    c2g, step = lt.nm("contact.space_to.gate"), lt.nm("poly.space_to.active")
    ext, pspace = lt.nm("active.extension.poly"), lt.space("poly")
    m1space = lt.space("metal1")
    out = []
    for i in range(len(devs) + 1):
        left = devs[i - 1] if i > 0 else None
        right = devs[i] if i < len(devs) else None
        gates = [d for d in (left, right) if d is not None]
        width = max([d.w for d in gates] + ([wc] if contacted[i] else []))
        # distance from a gate to the contact: more when the region widens past that gate
        c2 = [max(c2g, step + enc) if width > d.w else c2g for d in gates]
        if contacted[i]:
            n = cut + sum(c2) + (enc if len(gates) == 1 else 0)
        else:
            n = pspace
        if len(gates) == 2:
            n = max(n, pspace + (max(0, pad_h - left.l) + max(0, pad_h - right.l)) // 2,
                    m1pad + m1space - (left.l + right.l) // 2)
            if left.w != right.w:
                n = max(n, ext + step)
        else:
            n = max(n, ext)
        out.append(lt.snap_up(n))
    return out


def mos_strip(cv: Canvas, lt, kind: str, x0: int, y0: int, devs: list[Mos], nets: list[str],
              contacted: list[bool], pads: str = "right", stagger: int = 0) -> Strip:
    """Draw transistors in series along y from (x0, y0): ``nets`` = [sd0, g0, sd1, g1, ... sdN].

    The COMP is aligned on x0 (``pads="right"``: end caps left of x0, gate pads right of the
    strip) or on x0 from the right (``pads="left"``: mirror image). ``kind``: "n" or "p"
    (the implant; a p strip needs its n-well from the caller, see :func:`well`). ``stagger``:
    every second gate pad sits that much further out (two lanes for the gates' vias)."""
    n = len(devs)
    assert len(nets) == 2 * n + 1 and len(contacted) == n + 1
    cut, enc = lt.cut("contact"), lt.nm("contact.enclosure.active")
    m1pad = pad_side(lt, "metal1")
    wc = cut + 2 * enc
    pad_h = max(cut + 2 * lt.nm("poly.enclosure.contact"), m1pad)
    lengths = _region_lengths(lt, devs, contacted, wc, pad_h, m1pad)
    wmax = max([d.w for d in devs] + [wc if any(contacted) else 0])
    sgn = 1 if pads == "right" else -1

    def X(a: int, b: int) -> tuple[int, int]:     # local x (0 at the aligned edge) -> canvas x
        return (x0 + a, x0 + b) if sgn > 0 else (x0 - b, x0 - a)

    # y of each region and gate
    y = y0
    regions, gates = [], []
    for i in range(n + 1):
        regions.append((y, y + lengths[i]))
        y += lengths[i]
        if i < n:
            gates.append((y, y + devs[i].l))
            y += devs[i].l
    y_end = y
    out = Strip()
    step = lt.nm("poly.space_to.active")
    # COMP: each gate's width through its neighbour regions (stopping short of a narrower gate)
    for i, d in enumerate(devs):
        lo = regions[i][0] if i == 0 else gates[i - 1][1] + (step if devs[i - 1].w < d.w else 0)
        hi = regions[i + 1][1] if i == n - 1 else gates[i + 1][0] - (step if devs[i + 1].w < d.w else 0)
        xa, xb = X(0, d.w)
        cv.add("active", box(xa, lo, xb, hi), "")
    # contacts (at the aligned COMP edge) and their pads
    c2g = lt.nm("contact.space_to.gate")
    for i in range(n + 1):
        if not contacted[i]:
            out.sd.append((nets[2 * i], None))
            continue
        r0, r1 = regions[i]
        # at a strip end the contact sits at the end; between gates, past the lower gate's spacing
        left = devs[i - 1] if i > 0 else None
        right = devs[i] if i < n else None
        width = max([d.w for d in (left, right) if d is not None] + [wc])
        c2l = max(c2g, step + enc) if left is not None and width > left.w else c2g
        c2r = max(c2g, step + enc) if right is not None and width > right.w else c2g
        if i == 0:
            cy = r0 + enc + cut // 2
        elif i == n:
            cy = r1 - enc - cut + cut // 2
        else:
            slack = max(0, (r1 - r0) - c2l - c2r - cut)
            cy = r0 + c2l + cut // 2 + (slack // (2 * lt.grid)) * lt.grid
        xa, xb = X(0, wc)
        cv.add("active", box(xa, cy - cut // 2 - enc, xb, cy - cut // 2 + cut + enc), "")
        ccx = (xa + xb) // 2
        p = contact_pad(cv, lt, ccx, cy, "active", nets[2 * i])
        out.sd.append((nets[2 * i], p))
    # gates: poly across the COMP with the end cap, neck and contacted pad on the far side
    endcap = lt.nm("poly.extension.active")
    enc_m1 = (m1pad - cut) // 2
    cx0 = gate_contact_offset(lt, devs, contacted)
    penc = lt.nm("poly.enclosure.contact")
    for i, d in enumerate(devs):
        g0, g1 = gates[i]
        gc = lt.snap((g0 + g1) // 2)
        c0 = cx0 + (stagger if i % 2 else 0)
        a, b = X(-endcap, c0 + cut + penc)
        cv.add("poly", box(a, g0, b, g1), nets[2 * i + 1])
        a, b = X(c0 - penc, c0 + cut + penc)
        cv.add("poly", box(a, gc - pad_h // 2, b, gc - pad_h // 2 + pad_h), nets[2 * i + 1])
        a, b = X(c0, c0 + cut)
        p = contact_pad(cv, lt, (a + b) // 2, gc, "poly", nets[2 * i + 1])
        out.gates.append((nets[2 * i + 1], p))
    # implant around COMP and gates
    imp = "nplus" if kind == "n" else "pplus"
    e_comp, e_gate = lt.nm(f"{imp}.enclosure.active"), lt.nm(f"{imp}.enclosure.gate")
    a, b = X(-e_gate, wmax + e_gate)
    out.implant = cv.add(imp, box(a, y0 - e_comp, b, y_end + e_comp), "")
    a, b = X(0, wmax)
    out.comp = box(a, y0, b, y_end)
    a, b = X(-endcap, cx0 + (stagger if n > 1 else 0) + cut + max(penc, enc_m1))
    out.extent = box(min(a, out.implant.x0), out.implant.y0, max(b, out.implant.x1), out.implant.y1)
    return out


def gate_contact_offset(lt, devs: list[Mos], contacted: list[bool]) -> int:
    """Distance from a strip's aligned COMP edge to the near edge of its gate contacts: past the
    widest COMP by the poly-contact-to-COMP rule, and clear of the source/drain pads."""
    cut, enc = lt.cut("contact"), lt.nm("contact.enclosure.active")
    m1pad = pad_side(lt, "metal1")
    wc = cut + 2 * enc
    wmax = max([d.w for d in devs] + [wc if any(contacted) else 0])
    sd_pad_far = (wc + m1pad) // 2 if any(contacted) else 0
    enc_m1 = (m1pad - cut) // 2
    return lt.snap_up(max(wmax + lt.nm("contact.space_to.active"), sd_pad_far + lt.space("metal1") + enc_m1))


def strip_height(lt, devs: list[Mos], contacted: list[bool]) -> int:
    """The y extent of :func:`mos_strip`'s COMP for these devices (without implant margins)."""
    cut, enc = lt.cut("contact"), lt.nm("contact.enclosure.active")
    m1pad = pad_side(lt, "metal1")
    pad_h = max(cut + 2 * lt.nm("poly.enclosure.contact"), m1pad)
    return sum(_region_lengths(lt, devs, contacted, cut + 2 * enc, pad_h, m1pad)) + sum(d.l for d in devs)


def tap(cv: Canvas, lt, kind: str, cx: int, cy: int, net: str) -> tuple[Box, Box]:
    """A well / substrate tap centred on (cx, cy): COMP (big enough for its area rule), implant
    (``kind`` "p": P+ substrate tap, "n": N+ well tap), contact and metal1 pad.
    Returns (COMP box, metal1 pad)."""
    cut, enc = lt.cut("contact"), lt.nm("contact.enclosure.active")
    side = max(cut + 2 * enc, lt.snap_up(math.sqrt(lt.area("active.area"))))
    comp = square(cx, cy, side)
    imp = "pplus" if kind == "p" else "nplus"
    e = lt.nm(f"{imp}.enclosure.active")
    iside = max(side + 2 * e, lt.width(imp), lt.snap_up(math.sqrt(lt.area(f"{imp}.area"))))
    cv.add("active", comp, "")
    cv.add(imp, square(cx, cy, iside), "")
    return comp, contact_pad(cv, lt, cx, cy, "active", net)


def tap_size(lt, kind: str) -> tuple[int, int]:
    """(COMP side, implant side) of :func:`tap`."""
    cut, enc = lt.cut("contact"), lt.nm("contact.enclosure.active")
    side = max(cut + 2 * enc, lt.snap_up(math.sqrt(lt.area("active.area"))))
    imp = "pplus" if kind == "p" else "nplus"
    e = lt.nm(f"{imp}.enclosure.active")
    return side, max(side + 2 * e, lt.width(imp), lt.snap_up(math.sqrt(lt.area(f"{imp}.area"))))


def well(cv: Canvas, lt, comps: list[Box], net: str) -> Box:
    """The n-well around p-channel COMP boxes (enclosure rule), as one rectangle."""
    e = lt.nm("nwell.enclosure.pcomp")
    b = Box(min(c.x0 for c in comps) - e, min(c.y0 for c in comps) - e,
            max(c.x1 for c in comps) + e, max(c.y1 for c in comps) + e)
    w = lt.width("nwell")
    b = Box(b.x0, b.y0, max(b.x1, b.x0 + w), max(b.y1, b.y0 + w))
    return cv.add("nwell", b, net)


def photodiode(cv: Canvas, lt, pd: Box, contact_xy: tuple[int, int], net: str, sub_tap: Box) -> Box:
    """The n-well / p-substrate photodiode: the n-well ``pd`` (the junction the models use), an
    N+ contact at ``contact_xy`` inside it, and the technology's photodiode marker over the
    well and the P+ substrate tap ``sub_tap`` (the foundry LVS recognises the diode where the
    marker covers an n-well that covers N+ COMP, its p terminal being P+ COMP inside the
    marker). Returns the metal1 pad of the N+ contact."""
    cv.add("nwell", pd, net)
    _, m1 = tap(cv, lt, "n", contact_xy[0], contact_xy[1], net)
    m = lt.grid * 2
    assert sub_tap.x0 >= pd.x1 and pd.y0 <= sub_tap.cy <= pd.y1, "the substrate tap sits right of the PD"
    cv.add("pd_marker", pd.grown(m), "")
    cv.add("pd_marker", box(pd.x1 - m, sub_tap.y0 - m, sub_tap.x1 + m, sub_tap.y1 + m), "")  # bridge to the tap
    return m1


def pd_contact_inset(lt) -> int:
    """How far inside the PD's edge the centre of its N+ contact sits."""
    side, iside = tap_size(lt, "n")
    return max(lt.nm("nwell.enclosure.ncomp") + side // 2, iside // 2)


def resistor_heads(lt) -> int:
    """Length of poly a :func:`poly_resistor` adds beyond its body at each end (its contacted head)."""
    cut = lt.cut("contact")
    return lt.snap_up(max(lt.nm("poly.extension.sab"), lt.nm("sab.space_to.contact") + cut + lt.nm("poly.enclosure.contact")))


def poly_resistor(cv: Canvas, lt, x0: int, y0: int, w: int, length: int, bottom: str, top: str) -> dict:
    """An unsalicided P+ poly resistor along y: the body ``w`` x ``length`` from (x0, y0) under the
    salicide block and the resistor marker (their edges across the poly are the body's ends, as
    the foundry's RES_MK rule asks), a contacted head beyond each end, the P+ implant around all.
    Returns {"bottom": metal1 pad, "top": metal1 pad, "extent": the implant box}."""
    if w < lt.width("resistor"):
        raise ValueError(f"resistor width {w / 1000:g} um < {lt.cite('resistor.width')}")
    cut, penc = lt.cut("contact"), lt.nm("poly.enclosure.contact")
    head = resistor_heads(lt)
    enc_sab = lt.nm("sab.enclosure.resistor")
    sab = box(x0 - enc_sab, y0, x0 + w + enc_sab, y0 + length)
    if sab.w < lt.width("sab") or sab.w * sab.h < lt.area("sab.area"):
        raise ValueError(f"resistor body {w / 1000:g} x {length / 1000:g} um: its salicide block is under "
                         f"{lt.cite('sab.width')} / {lt.tech.rule('sab.area').value * 1e12:g} um2")
    cv.add("poly", box(x0, y0 - head, x0 + w, y0), bottom)
    cv.add("poly", box(x0, y0, x0 + w, y0 + length), "")
    cv.add("poly", box(x0, y0 + length, x0 + w, y0 + length + head), top)
    cv.add("sab", sab, "")
    cv.add("res_marker", sab, "")
    e = lt.nm("pplus.enclosure.resistor")
    ext = cv.add("pplus", box(x0 - e, y0 - head - e, x0 + w + e, y0 + length + head + e), "")
    cx = x0 + w // 2
    out = {"extent": ext}
    for net, cy in ((bottom, y0 - head + penc + cut // 2), (top, y0 + length + head - penc - cut + cut // 2)):
        out["bottom" if net == bottom else "top"] = contact_pad(cv, lt, cx, cy, "poly", net)
    return out


def top_metal_space(lt) -> int:
    """Spacing to the top metal's wide shapes (a MIM plate, the shield): the wide-metal rule
    where the technology has one."""
    return lt.nm("shield.space") if lt.has("shield.space") else lt.space("metal5")


def mim_extension(lt) -> int:
    """How far a :func:`mim_cap`'s bottom plate reaches beyond the top plate on its via side:
    the via clear of the top plate (MIMTM.5), its top-metal pad clear of the plate's top metal,
    the bottom plate around the via (MIMTM.2)."""
    vs = lt.cut("via4")
    side = pad_side(lt, "metal5")
    to_via = max(lt.nm("mim_top.space_to.via4"), top_metal_space(lt) + (side - vs) // 2)
    return max(lt.nm("mim_bottom.enclosure.mim_top"), to_via + vs + lt.nm("mim_bottom.enclosure.via4"))


def mim_cap(cv: Canvas, lt, x0: int, y0: int, w: int, h: int, top: str, bottom: str, via_side: str = "right") -> dict:
    """A MIM capacitor (top plate ``w`` x ``h`` at (x0, y0)): bottom plate on ``mim_bottom``
    enclosing it, the marker layers, a sea of vias from the top plate to the metal above and one
    via from the bottom plate's extension on ``via_side`` ("right" / "left") up, its top-metal pad
    clear of the plate's. Returns {"top": metal box, "bottom": metal box, "plate": bottom plate}."""
    tp = box(x0, y0, x0 + w, y0 + h)
    area_min = lt.area("mim_top.area")
    if w * h < area_min:
        raise ValueError(f"MIM top plate {w * h / 1e6:g} um2 < {lt.cite('mim_top.area')}")
    e_bot = lt.nm("mim_bottom.enclosure.mim_top")
    via = "via4"
    vs, venc = lt.cut(via), lt.nm("mim_top.enclosure.via4")
    upper = "metal5"
    shapes = [("mim_top", tp, top), ("mim_marker", tp.grown(e_bot), "")]
    if lt.tech.layout.layers.get("mim_l_marker") is not None:
        shapes.append(("mim_l_marker", tp.grown(e_bot), ""))
    # top plate: vias at the sea-of-via spacing, the upper metal over them
    pitch = vs + lt.nm("mim_via.space")
    nx = max(1, (w - 2 * venc - vs) // pitch + 1)
    ny = max(1, (h - 2 * venc - vs) // pitch + 1)
    g = lt.grid   # the sea centred, on the drawing grid
    ox = x0 + (w - (nx - 1) * pitch - vs) // (2 * g) * g
    oy = y0 + (h - (ny - 1) * pitch - vs) // (2 * g) * g
    for i in range(nx):
        for j in range(ny):
            shapes.append((via, box(ox + i * pitch, oy + j * pitch, ox + i * pitch + vs, oy + j * pitch + vs), top))
    shapes.append((upper, tp, top))
    # bottom plate with an extension carrying its via (drawn on the right, mirrored for the left)
    ext = mim_extension(lt)
    bx1 = x0 + w + ext
    bot = box(x0 - e_bot, y0 - e_bot, bx1, y0 + h + e_bot)
    vx = bx1 - lt.nm("mim_bottom.enclosure.via4") - vs
    vy = y0 + (h // 2 - vs // 2) // g * g
    side = pad_side(lt, upper)
    shapes += [("mim_bottom", bot, bottom), (via, box(vx, vy, vx + vs, vy + vs), bottom),
               (upper, square(vx + vs // 2, vy + vs // 2, side), bottom)]
    if via_side == "left":          # mirror about the plate's centre line
        shapes = [(lay, box(2 * x0 + w - b.x1, b.y0, 2 * x0 + w - b.x0, b.y1), n) for lay, b, n in shapes]
    for lay, b, n in shapes:
        cv.add(lay, b, n)
    top_metal = next(b for lay, b, n in shapes if lay == upper and n == top)
    return {"top": top_metal, "bottom": shapes[-1][1], "plate": shapes[-3][1]}
