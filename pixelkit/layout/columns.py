"""The column circuit drawn from ``circuits.column.column_cell`` - the load bias NMOS, the line's
current-source load, the S1X / S2X transmission gates and, when the array reads with one, the
column precharge switch - and the dual pixel with its columns.

A column cell is as wide as the column pitch it serves (8 um under a secondary column, 24 um
over the primary one: column-parallel circuits are tall and narrow). From the edge away from
the array: the P+ substrate tap, the load / bias strip (col | LOAD | vss | BIAS | nbias), with a
precharge its strip (vss | PRE | col), the N-channel sampler strip (out | S1 | col | S2 | out)
and the P-channel one in its n-well (with the well's N+ tap). The clocks and supplies (s1, s1b,
s2, s2b, pre, vdd, vss) are full-width metal3 lines; ``col`` continues the array's column line
(metal4, same x) and ``out`` / ``nbias`` leave on metal4 tracks on the other side, at x the dual
pixel leaves free.
"""
from __future__ import annotations

from ..circuits.column import precharged
from .canvas import Canvas, box
from .dual import SUPPLIES
from .primitives import Mos, finger_nets, fold, mos_strip, pad_side, tap, tap_size, well
from .route import Lines, RouteError, route_all, route_to_line, stub_to_track, track, via_on
from .rules import RuleError


def _sizes(design, lt):
    dev = design.pixel.devices
    out = {}
    for name, field, mult in (("load", "load", 1), ("sw", "sw", 1), ("swp", "sw", 2)):
        w = lt.size_nm(getattr(dev, f"{field}_w"), f"pixel.devices.{field}_w", "column cell", "active.width")
        l_ = lt.size_nm(getattr(dev, f"{field}_l"), f"pixel.devices.{field}_l", "column cell",
                        low=lt.snap_up(design.tech.mos.lmin * 1e9), low_rule="mos.lmin")
        out[name] = (w * mult, l_)
    return out


# the three strips, each two devices in series sharing a terminal: (name, size key, field, a, gate, b),
# the strip running a -> b -> (the next device) as drawn unfolded
STRIPS = {"load": (("ld", "load", "load_w", "col", "nbias", "vss"), ("bias", "load", "load_w", "vss", "nbias", "nbias")),
          "sw": (("s1n", "sw", "sw_w", "out", "s1", "col"), ("s2n", "sw", "sw_w", "col", "s2", "out")),
          "swp": (("s1p", "swp", "sw_w", "out", "s1b", "col"), ("s2p", "swp", "sw_w", "col", "s2b", "out"))}
#: the precharge switch (``circuits.column.precharge``: the samplers' size), a strip of its own
PRE = (("pre", "sw", "sw_w", "vss", "pre", "col"),)


def _strips_of(design, kind: str) -> dict:
    """The strips of ``kind``'s column cell: ``STRIPS`` and, when the array has a precharge, ``pre``."""
    return {**STRIPS, "pre": PRE} if precharged(design, kind) else STRIPS


def _stack_gap(lt) -> int:
    """COMP gap above the precharge strip: its top pad (col) and the sampler strip's first (col
    when its devices fold into an even number of fingers) both stack to the col track, so their
    metal1 - metal3 pads keep the metals' spacing."""
    cut, enc = lt.cut("contact"), lt.nm("contact.enclosure.active")
    room = max(pad_side(lt, m) + lt.space(m) for m in ("metal1", "metal2", "metal3"))
    return lt.snap_up(max(lt.space("active"), room - 2 * enc - cut))


def _strip(sz: dict, devs, folds: dict) -> tuple[list, list]:
    """Transistors and nets of a strip, each device folded into ``folds[name]`` = (n, finger W)."""
    mos, nets = [], []
    for i, (name, key, _, a, g, b) in enumerate(devs):
        n, wf = folds.get(name, (1, sz[key][0]))
        start = nets[-1] if nets else (b if n % 2 == 0 else a)     # the first ends on b, shared with the next
        nets += finger_nets(a, g, b, n, start)[1 if nets else 0:]
        mos += [Mos(name, wf, sz[key][1])] * n
    return mos, nets


def _folds(design, lt, sz: dict, strips: dict, x_r: int, edge: int, name: str) -> dict:
    """Fingers per device: each strip's devices no wider than leaves its gate pads and well
    (measured on the strip drawn unfolded) ``edge`` from the cell's left edge."""
    out = {}
    nw_e = lt.nm("nwell.enclosure.pcomp")
    for key, devs in strips.items():
        trial = Canvas("trial", lt)
        mos, nets = _strip(sz, devs, {})
        st = mos_strip(trial, lt, "p" if key == "swp" else "n", x_r, 0, mos, nets, [True] * (len(mos) + 1), "left")
        left = min(st.extent.x0, st.comp.x0 - (nw_e if key == "swp" else 0))
        wmax = ((max(m.w for m in mos) - (edge - left)) // lt.grid) * lt.grid
        for dev, size, field, *_ in devs:
            w = sz[size][0]
            if w <= wmax:
                continue
            got = fold(lt, w, wmax)
            if got is None:
                value = getattr(design.pixel.devices, field)
                raise RuleError("transistors_fit", f"{name} cell", f"{dev} (W {w / 1000:g} um) cannot be folded "
                                f"into fingers of at most {max(wmax, 0) / 1000:g} um (the column pitch less its gate "
                                f"pads, well and tracks) on the {lt.grid} nm grid", f"pixel.devices.{field}", value)
            out[dev] = got
    return out


def _spines(cv: Canvas, lt, strip) -> None:
    """Metal1 joining the gate pads of one net's fingers, along their outer edge."""
    w1 = lt.width("metal1")
    runs: list = []
    for net, p in strip.gates:
        if runs and runs[-1][0] == net:
            runs[-1][1].append(p)
        else:
            runs.append((net, [p]))
    for net, pads in runs:
        if len(pads) > 1:
            cv.add("metal1", box(pads[0].x0, pads[0].cy, pads[0].x0 + w1, pads[-1].cy), net)


def column_cell(design, lt, kind: str, width: int, tracks: dict, reserved: list, array_side: str,
                place_only: bool = False) -> Canvas:
    """The column cell of ``kind`` ("primary" / "secondary"), ``width`` nm wide; ``tracks``: the
    metal4 x of col, out and nbias; ``reserved``: metal4 x ranges to leave free; ``array_side``:
    "top" (the cell sits under the array) or "bottom"."""
    name = "COLUMN_P" if kind == "primary" else "COLUMN_S"
    cv = Canvas(name, lt)
    sz = _sizes(design, lt)
    pad4 = pad_side(lt, "metal4")
    for x0, x1 in reserved:
        cv.block(["metal4"], box(x0, -10 ** 6, x1, 10 ** 6), "#reserved")
    x_r = min(tracks.values()) - pad4 // 2 - lt.space("metal4") - pad_side(lt, "metal1")
    x_r = (x_r // lt.grid) * lt.grid
    side, iside = tap_size(lt, "p")
    enc_np = lt.nm("nplus.enclosure.active")
    y = lt.space("nplus") // 2 + iside // 2
    tap_p = tap(cv, lt, "p", x_r - side // 2, y, "vss")
    y = y - side // 2 + max(iside // 2 + enc_np + side // 2, side + lt.space("active"))
    plan = _strips_of(design, kind)
    folds = _folds(design, lt, sz, plan, x_r, lt.space("nwell") // 2, name)
    strips = {k: _strip(sz, devs, folds) for k, devs in plan.items()}
    a = mos_strip(cv, lt, "n", x_r, y, *strips["load"], [True] * (len(strips["load"][0]) + 1), "left")
    pre = [mos_strip(cv, lt, "n", x_r, a.comp.y1 + lt.space("active"), *strips["pre"],
                     [True] * (len(strips["pre"][0]) + 1), "left")] if "pre" in strips else []
    y = pre[0].comp.y1 + _stack_gap(lt) if pre else a.comp.y1 + lt.space("active")
    b = mos_strip(cv, lt, "n", x_r, y, *strips["sw"],
                  [True] * (len(strips["sw"][0]) + 1), "left")
    nw_e = lt.nm("nwell.enclosure.pcomp")
    yc = b.comp.y1 + lt.nm("nwell.space_to.ncomp") + nw_e
    c = mos_strip(cv, lt, "p", x_r, lt.snap_up(yc), *strips["swp"], [True] * (len(strips["swp"][0]) + 1), "left")
    nside, niside = tap_size(lt, "n")
    ty = c.comp.y1 + max(lt.space("active"), lt.nm("pplus.enclosure.active") + lt.nm("pplus.space_to.active"),
                         lt.nm("nplus.space_to.active") + (niside - nside) // 2) + nside // 2
    ty = lt.snap_up(ty)
    ntap_comp, tap_n = tap(cv, lt, "n", x_r - nside // 2, ty, "vdd")
    nw = well(cv, lt, [c.comp, ntap_comp], "vdd")
    height = lt.snap_up(nw.y1 + lt.space("nwell") // 2 + lt.space("nwell") // 2)
    if min(*(st.extent.x0 for st in (a, *pre, b, c)), nw.x0) < lt.space("nwell") // 2:
        raise RuleError("transistors_fit", f"{name} cell", f"the column circuit needs "
                        f"{(width - min(a.extent.x0, nw.x0) + lt.space('nwell')) / 1000:g} um of the "
                        f"{width / 1000:g} um column pitch", "pixel.devices.sw_w", design.pixel.devices.sw_w)
    cv.add("boundary", box(0, 0, width, height), "")
    if place_only:
        return cv
    # per-column nets: metal4 tracks; col toward the array, out / nbias away from it
    pre_sd = [t for st in pre for t in st.sd]
    terms = {"col": [p for n, p in a.sd + pre_sd + b.sd + c.sd if n == "col"],
             "out": [p for n, p in b.sd + c.sd if n == "out"], "nbias": [p for n, p in a.sd if n == "nbias"]}
    # nbias: the bias device is diode-connected, every gate of the strip tied to its drain on metal1
    for st in (*pre, b, c):
        _spines(cv, lt, st)
    g_ld, nb = a.gates[0][1], terms["nbias"][0]
    w1 = lt.width("metal1")
    ys = [p.cy for _, p in a.gates] + [nb.cy]
    cv.add("metal1", box(g_ld.x0, min(ys), g_ld.x0 + w1, max(ys)), "nbias")
    cv.add("metal1", box(g_ld.x0, nb.y0, nb.x1, nb.y1), "nbias")
    for net, pads in terms.items():
        x = tracks[net]
        for p in pads:
            stub_to_track(cv, lt, net, p, x, "metal4")
        rows = [p.cy for p in pads]
        toward = (net == "col") == (array_side == "top")
        y0, y1 = (min(rows), height) if toward else (0, max(rows))
        track(cv, lt, net, "metal4", x, y0, y1)
        cv.label("metal4_label", x, (y0 + y1) // 2, net)
    half = lt.space("metal3") // 2
    lines = Lines("metal3", 0, width, [(half, height - half)])
    first = {n: p for n, p in reversed(b.gates + c.gates)}
    vss = [p for n, p in a.sd + pre_sd if n == "vss"]
    terminals = {"s1": first["s1"], "s2": first["s2"], "s1b": first["s1b"], "s2b": first["s2b"],
                 "vss": vss[0], "vdd": tap_n, **{"pre": st.gates[0][1] for st in pre}}
    route_all(cv, lt, lines, terminals, sorted(terminals, key=lambda n: terminals[n].cy))
    for p in vss[1:]:                                      # a folded load's other sources, the precharge's
        route_to_line(cv, lt, lines, "vss", p)
    route_to_line(cv, lt, lines, "vss", tap_p[1])          # the substrate tap onto the vss line
    cv.ports = {"lines": dict(lines.y), "height": height, "tracks": dict(tracks)}
    return cv


def _edge_tracks(cv: Canvas, y: int, layer: str = "metal4") -> list:
    """x ranges of the ``layer`` shapes of ``cv`` (with placed cells) that reach height y."""
    return sorted({(s.box.x0, s.box.x1) for s in cv.shapes_on(layer) if not s.net.startswith("#")
                   and s.box.y0 <= y <= s.box.y1})


def _pick(xs, taken, n, pad):
    out = []
    for x in xs:
        if all(x + pad // 2 + 280 <= a or x - pad // 2 - 280 >= b for a, b in taken):
            out.append(x)
            taken = taken + [(x - pad // 2, x + pad // 2)]
            if len(out) == n:
                return out
    raise RouteError("column cell", "out", "no free metal4 track for out / nbias")


def dual_pixel_column(design, lt, dual: Canvas) -> tuple[dict, Canvas]:
    """COLUMN_P, COLUMN_S and DUALPIX_COL around the drawn DUALPIX."""
    n = design.secondary_per_pixel
    ps, pp = lt.snap(design.secondary.pitch * 1e9), lt.snap(design.primary.pitch * 1e9)
    hd = dual.ports["height"]
    pad4, s4 = pad_side(lt, "metal4"), lt.space("metal4")
    pitch = pad4 + s4
    # under the secondaries: what DUALPIX brings down to its bottom edge, in one secondary's x
    bottom = _edge_tracks(dual, 0)
    local = [(a - k * ps, b - k * ps) for a, b in bottom for k in range(n) if 0 <= a - k * ps < ps]
    xcs = dual.ports["col_s0"][1]
    o, nb = _pick([xcs - pitch * i for i in range(1, 30)], [r for r in local if not (r[0] <= xcs <= r[1])], 2, pad4)
    cs = column_cell(design, lt, "secondary", ps, {"col": xcs, "out": o, "nbias": nb},
                     [r for r in local if not (r[0] <= xcs <= r[1])], "top")
    top_edge = _edge_tracks(dual, hd)
    xcp = dual.ports["col_p"][1]
    others = [r for r in top_edge if not (r[0] <= xcp <= r[1])]
    o, nb = _pick([xcp - pitch * i for i in range(1, 40)], others, 2, pad4)
    cp = column_cell(design, lt, "primary", pp, {"col": xcp, "out": o, "nbias": nb}, others, "bottom")
    hs = cs.ports["height"]
    top = Canvas("DUALPIX_COL", lt)
    for k in range(n):
        top.place(cs, k * ps, 0, {"col": f"col_s{k}", "out": f"out_s{k}", "nbias": f"nbias_s{k}",
                                   "s1": "s1_s", "s1b": "s1b_s", "s2": "s2_s", "s2b": "s2b_s", "pre": "pre_s",
                                   "vdd": "vdd", "vss": "vss"}, name=f"xcs{k}")
    dual_nets = {p: p for p in ("vdd", "vpdr", "vrst", "vss", "col_p", *(f"col_s{k}" for k in range(n)),
                                *(f"{c}_{a}" for c in ("ec", "tg", "rst", "rs") for a in ("p", "s")))}
    top.place(dual, 0, hs, dual_nets, name="xpix")
    top.place(cp, 0, hs + hd, {"col": "col_p", "out": "out_p", "nbias": "nbias_p", "s1": "s1_p",
                               "s1b": "s1b_p", "s2": "s2_p", "s2b": "s2b_p", "pre": "pre_p", "vdd": "vdd",
                               "vss": "vss"},
              name="xcp")
    # vdd and vss: the dual pixel's metal4 verticals on through the column cells, onto their lines
    for net in ("vdd", "vss"):
        xs = {s.box.cx for s in dual.shapes_on("metal4") if s.net == net and s.box.y0 == 0 and s.box.y1 == hd}
        if not xs:
            raise RouteError("DUALPIX_COL", net, "no supply track in the dual pixel")
        x = min(xs)
        track(top, lt, net, "metal4", x, 0, hs)
        via_on(top, lt, net, x, cs.ports["lines"][net], "metal3", "metal4")
        hc = cp.ports["height"]
        track(top, lt, net, "metal4", x, hs + hd, hs + hd + hc)
        via_on(top, lt, net, x, hs + hd + cp.ports["lines"][net], "metal3", "metal4")
    # the dual pixel's own ports, named again at this level (its row lines and supply tracks)
    w3 = lt.width("metal3")
    for c in ("ec", "tg", "rst", "rs"):
        top.label("metal3_label", w3, hs + dual.ports["lines_s"][c], f"{c}_s")
        top.label("metal3_label", w3, hs + ps + dual.ports["lines_p"][c], f"{c}_p")
    for net in SUPPLIES:
        top.label("metal3_label", w3, hs + dual.ports["lines_s"][net], net)
    for net, y in cs.ports["lines"].items():
        if net not in SUPPLIES:
            top.label("metal3_label", lt.width("metal3"), y, f"{net}_s")
    for net, y in cp.ports["lines"].items():
        if net not in SUPPLIES:
            top.label("metal3_label", lt.width("metal3"), hs + hd + y, f"{net}_p")
    for k in range(n):
        for net in ("out", "nbias"):
            top.label("metal4_label", k * ps + cs.ports["tracks"][net], 1, f"{net}_s{k}")
    for net in ("out", "nbias"):
        top.label("metal4_label", cp.ports["tracks"][net], hs + hd + cp.ports["height"] - 1, f"{net}_p")
    total = hs + hd + cp.ports["height"]
    top.add("boundary", box(0, 0, pp, total), "")
    top.ports = {"width": pp, "height": total}
    return {"COLUMN_P": cp, "COLUMN_S": cs}, top
