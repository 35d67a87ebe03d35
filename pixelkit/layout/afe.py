"""The switched-capacitor AFE drawn from its netlist (``circuits.readout.afe_cell``: ``sc_afe`` on
the transistor-level ``opamp_ota``), one cell per column at the column's pitch.

A column-parallel readout is a tall, narrow cell: everything is stacked along y in the
column's width. From the bottom edge (away from the array) up:

- the pins ``out``, ``nb`` (the op-amp's bias current) and the column bias ``nbias`` passing
  through, as metal4 stubs at the bottom edge;
- the op-amp's compensation capacitor ``Cc`` and resistor ``Rz``;
- the op-amp's N-channel devices (one strip each, wide ones folded into fingers of equal W that
  LVS adds back up), a P+ substrate tap; its P-channel devices in one n-well with its N+ tap;
- the horizontal lines every column shares (abutting cells join them): ``vss vdd vref p1 p1b
  p2 p2b``;
- the transmission-gate switches (a tap, N strips; P strips in their n-well, a tap), each group
  ordered and each strip turned (``_switch_plan``) so the floating nodes' pads face only their
  own net, vref or a tap: the feedback switch's x beside the tap at both ends;
- the MIM capacitors C13, C12, C11 (the technology's MIM device with its markers): their top
  plates are the shared node ``vm``, their bottom plates ``c``, ``x``, ``in``;
- at the top edge the column circuit's ``out`` (the AFE input ``in``) and ``nbias`` arrive on
  metal4 at the x the column cell above leaves them.

Every MOSFET, capacitor and resistor is an element of the netlist with its W / L or value:
the capacitor's plate is as wide as the pitch allows and as long as its value asks (the
model card's area and perimeter capacitance), the resistor's body as long as its value asks
at the technology's sheet resistance. The capacitors' plates leave on planned top-metal leads
to metal4 landings (:mod:`.mimstack`); every net is then routed by :mod:`.gridroute` on metal2 -
metal4, keeping metal4 1.2 um (the MIM rule) off every capacitor's bottom plate. The SC stage's
floating nodes (``GUARDED``: the op-amp input ``x``, the shared node ``vm``) are routed first, and
the grid points beside, over and under their routes are filled with vss metal tied to vss
(``GridRouter.guards``): no node that moves between the phases runs next to them.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..circuits.readout import afe_cell, opamp_cell
from .canvas import Box, Canvas, box
from .gridroute import GridRouter, Terminal
from .mimstack import column, draw_stack
from .primitives import Mos, finger_nets, fold, mos_strip, pad_side, poly_resistor, resistor_heads, strip_height, tap, tap_size, well
from .route import track
from .rules import RuleError

#: the lines every AFE of a row of columns shares, bottom first
LINES = ("vss", "vdd", "vref", "p1", "p1b", "p2", "p2b")
PINS_BOTTOM = ("nb", "out", "nbias")
GROUP_GAP = 1200        # nm between device groups (wells, implants, resistor rules all kept)
STRIP_GAP = 800         # nm between strips of one group (their implants merge or keep NP.2 / PP.2)
CAP_GAP = 2500          # nm of routing room between the capacitors and the devices (MIM: metal4 1.2 um off)
#: the SC stage's floating nodes (the op-amp's input x and the capacitors' shared node vm hold their
#: charge while C13 transfers it): routed first and shielded by vss, so no node that moves between the
#: phases (in, out, c) couples to them (docs/revisions.md: the GF180 revision B's post-layout gain error)
GUARDED = {"x": "vss", "vm": "vss"}
TAPS = {"vss", "vdd"}


@dataclass(frozen=True)
class Device:
    name: str
    kind: str           # "n" / "p" / "c" / "r"
    nodes: tuple
    w: float = 0.0
    l: float = 0.0
    value: float = 0.0


def afe_devices(design) -> list[Device]:
    """The AFE's devices, the op-amp flattened into it (its pins renamed to the AFE's nets)."""
    op, afe = opamp_cell(design), afe_cell(design, "secondary")
    t = design.tech
    params = dict(afe.params)
    out = []

    def node(n, m=None):
        n = (m or {}).get(n, n)
        return "vss" if n == "0" else n

    def add(e, m=None):
        k = e.name[0].upper()
        if k in "XM" and e.value in (t.mos.nmos, t.mos.pmos):
            p = dict(e.params)
            out.append(Device(e.name, "n" if e.value == t.mos.nmos else "p", tuple(node(n, m) for n in e.nodes),
                              p["w"], p["l"]))
        elif k == "C":
            v = e.value
            v = params[v.name] if hasattr(v, "name") else float(v)
            out.append(Device(e.name, "c", tuple(node(n, m) for n in e.nodes), value=v))
        elif k == "R":
            out.append(Device(e.name, "r", tuple(node(n, m) for n in e.nodes), value=float(e.value)))
        elif k == "X" and e.value == op.name:
            inner = dict(zip(op.ports, e.nodes))
            for f in op.elements:
                add(f, inner)
        else:
            raise ValueError(f"the AFE layout cannot draw element {e.name} ({e.value})")
    for e in afe.elements:
        add(e)
    return out


def _fingers(lt, dev: Device, wmax: int, field: str, value, place: str) -> tuple[int, int]:
    """(number of fingers, finger W in nm) of a device at most ``wmax`` wide per finger."""
    w = round(dev.w * 1e9)
    got = fold(lt, w, wmax)
    if got is None:
        raise RuleError("afe_fit", place, f"{dev.name} (W {w / 1000:g} um) cannot be folded into fingers of "
                        f"at most {wmax / 1000:g} um (the pitch less 4 um of gate pads and wells) on the {lt.grid} nm grid",
                        field, value)
    return got


def _finger_nets(dev: Device, n: int) -> list[str]:
    d, g, s, _ = dev.nodes
    return finger_nets(d, g, s, n, s if n % 2 == 0 else d)


def cap_plate(lt, tech, c: float, w: int) -> int:
    """Length (nm, on the grid) of a ``w`` nm wide MIM top plate of capacitance ``c`` (F)."""
    pa = tech.passives
    wm = w * 1e-9
    length = (c - 2 * pa.mim_c_perimeter * wm) / (pa.mim_c_area * wm + 2 * pa.mim_c_perimeter)
    return lt.snap(length * 1e9)


def cap_width(lt, width: int) -> int:
    """The widest MIM top plate a ``width`` nm cell holds (``mimstack.column``)."""
    return column(lt, width).plate_w


def resistor_length(lt, tech, r: float, w: int) -> int:
    """Body length (nm, on the grid) of a ``w`` nm wide resistor of ``r`` Ohm."""
    return lt.snap(r / tech.passives.res_sheet * w)


def drawn_size(design, circuit: str, kind: str, value: float) -> tuple:
    """(W, L) in um of the MIM plate (``kind`` "c") or resistor body ("r") the AFE of circuit
    ``afe_<primary|secondary>`` draws for ``value``."""
    from .techview import LayoutTech
    lt = LayoutTech(design.tech)
    which = circuit.rpartition("_")[2]
    if kind == "r":
        w = lt.width("resistor")
        return w / 1000, resistor_length(lt, design.tech, value, w) / 1000
    if which not in ("primary", "secondary"):
        return 0.0, 0.0
    w = cap_width(lt, lt.snap(getattr(design, which).pitch * 1e9))
    return w / 1000, cap_plate(lt, design.tech, value, w) / 1000


def _cell(which: str) -> str:
    return "AFE_P" if which == "primary" else "AFE_S"


def _fit(design, lt, width: int, which: str, devs: list[Device]) -> dict:
    """Sizes of what is drawn, or a RuleError naming the field that does not fit."""
    pitch_field = f"{which}.pitch"
    pitch_value = getattr(design, which).pitch
    wp = cap_width(lt, width)
    amin = lt.area("mim_top.area")
    side_min = 2 * lt.nm("mim_top.enclosure.via4") + lt.cut("via4")     # one via of the sea
    if wp < side_min:
        raise RuleError("afe_fit", f"{_cell(which)} cell", f"the MIM capacitors need a plate at least "
                        f"{side_min / 1000:g} um wide (a via enclosed by {lt.cite('mim_top.enclosure.via4')}) beside "
                        f"their bottom plates' vias and lanes: the {width / 1000:g} um pitch leaves {wp / 1000:g} um; "
                        f"the pitch must be at least {(width - wp + side_min) / 1000:g} um", pitch_field, pitch_value)
    out = {"plate_w": wp, "caps": {}, "fingers": {}}
    pa = design.tech.passives
    for d in devs:
        if d.kind == "c":
            length = cap_plate(lt, design.tech, d.value, wp)
            field = {"C11": "afe.c11", "C12": "afe.c12", "C13": "afe.c13"}.get(d.name, "")
            if length * wp < amin:
                need = pa.mim_value(math.sqrt(amin) * 1e-9, math.sqrt(amin) * 1e-9)
                raise RuleError("mim_top.area", f"{_cell(which)} cell", f"{d.name} = {d.value * 1e15:g} fF "
                                f"is a {wp / 1000:g} x {length / 1000:g} um plate, under the MIM's "
                                f"{amin / 1e6:g} um2 ({lt.tech.rule('mim_top.area').name}): at least "
                                f"{need * 1e15:.0f} fF", field, d.value)
            if length * wp > 1e10:    # MIMTM.8b: 10000 um2 per capacitor
                raise RuleError("mim_size", f"{_cell(which)} cell", f"{d.name} = {d.value * 1e15:g} fF needs "
                                f"{length * wp / 1e6:.0f} um2 of plate, over the 10000 um2 of one MIM capacitor",
                                field, d.value)
            out["caps"][d.name] = length
    wmax = max(lt.width("active"), ((width - 4000) // lt.grid) * lt.grid)
    for d in devs:
        if d.kind in "np":
            out["fingers"][d.name] = _fingers(lt, d, wmax, pitch_field, pitch_value, f"{_cell(which)} cell")
    return out


def _strip_devs(lt, dev: Device, n: int, wf: int):
    return [Mos(dev.name, wf, lt.snap(dev.l * 1e9))] * n, _finger_nets(dev, n)


class Stack:
    """Items placed bottom-up at the cell's left margin, and the terminals they leave."""

    def __init__(self, cv: Canvas, lt, x_left: int, y: int):
        self.cv, self.lt, self.x, self.y = cv, lt, x_left, y
        self.terms: dict = {}
        self.prev = None        # the last source / drain pad of the strip below in this group

    def term(self, net: str, layer: str, b: Box) -> None:
        self.terms.setdefault(net, []).append(Terminal(layer, b))

    def strip(self, dev: Device, n: int, wf: int, kind: str, flip: bool = False):
        lt = self.lt
        devs, nets = _strip_devs(lt, dev, n, wf)
        if flip:
            nets = nets[::-1]
        contacted = [True] * (len(devs) + 1)
        e = lt.nm(f"{'nplus' if kind == 'n' else 'pplus'}.enclosure.active")
        y0 = self.y + e
        s = mos_strip(self.cv, lt, kind, self.x, y0, devs, nets, contacted, "right")
        for net, p in s.sd + s.gates:
            self.term(net, "metal1", p)
        self._join(s)
        self.y = y0 + strip_height(lt, devs, contacted) + e
        return s

    def _join(self, s) -> None:
        """Two facing pads of one net in neighbouring strips, one of them beside a floating node's pad in
        its own strip: joined on metal1, and only the other lands (no landing and access wire of a node
        that moves between the phases beside the floating node's)."""
        prev, self.prev = self.prev, (s.sd[-1], s.sd[-2][0])
        if prev is None:
            return
        (net, a), beside_a = prev
        (net_b, b), beside_b = s.sd[0], s.sd[1][0]
        if net != net_b or net in GUARDED or a is None or b is None or not ({beside_a, beside_b} & set(GUARDED)):
            return
        self.cv.add("metal1", box(min(a.x0, b.x0), a.y0, max(a.x1, b.x1), b.y1), net)
        drop = a if beside_a in GUARDED else b
        self.terms[net] = [t for t in self.terms[net] if t.box != drop]

    def tap(self, kind: str, net: str):
        self.prev = None
        side, iside = tap_size(self.lt, kind)
        cx, cy = self.x + iside // 2, self.y + iside // 2
        comp, pad = tap(self.cv, self.lt, kind, cx, cy, net)
        self.term(net, "metal1", pad)
        self.y += iside
        return comp


def afe_layout(design, lt, which: str, width: int, x_in: int, x_pass: int, name: str) -> Canvas:
    """The AFE cell of a ``which`` column ("primary" / "secondary"), ``width`` nm wide, its input
    arriving on metal4 at x = ``x_in`` at the top edge and the column bias ``nbias`` at
    ``x_pass`` (continued to the bottom edge)."""
    devs = afe_devices(design)
    fit = _fit(design, lt, width, which, devs)
    cv = Canvas(name, lt)
    w4 = lt.width("metal4")
    x_left = lt.snap_up(lt.space("nwell") // 2 + lt.nm("nwell.enclosure.pcomp"))
    x_left = max(x_left, lt.nm("mim_bottom.space") // 2 + lt.nm("mim_bottom.enclosure.mim_top"))
    st = Stack(cv, lt, x_left, 0)
    router_pitch = pad_side(lt, "metal4") + lt.space("metal4")
    # bottom edge: pins on metal4 (grid columns, so the router lands on them straight)
    half = max(lt.space(m) for m in ("metal2", "metal3", "metal4")) // 2
    g0 = half + pad_side(lt, "metal4") // 2
    bottom_x = {}
    col = 1
    for net in PINS_BOTTOM:
        if net == "nbias":
            bottom_x[net] = x_pass
            continue
        x = g0 + col * router_pitch
        while any(abs(x - xx) < router_pitch for xx in (x_pass, *bottom_x.values())):
            col += 1
            x = g0 + col * router_pitch
        bottom_x[net] = x
        col += 2
    stub = lt.snap_up(pad_side(lt, "metal4") + lt.space("metal4"))
    for net, x in bottom_x.items():
        b = track(cv, lt, net, "metal4", x, 0, stub)
        st.term(net, "metal4", b)
        cv.label("metal4_label", x, stub // 2, net)
    y = stub + lt.nm("mim_bottom.space") + lt.space("metal4")
    # Cc (the op-amp's compensation), then Rz
    caps = [d for d in devs if d.kind == "c"]
    shared = _shared_node(caps)
    col = column(lt, width)

    def stack(ds, y):
        spec = []
        for d in ds:
            top = shared if shared in d.nodes else d.nodes[0]
            spec.append((top, d.nodes[1] if d.nodes[0] == top else d.nodes[0], fit["caps"][d.name]))
        s_ = draw_stack(cv, lt, col, spec, y)
        for net, pads in s_.landings.items():
            for b in pads:
                st.term(net, "metal4", b)
        keep = lt.nm("mim_bottom.space") - lt.space("metal4")
        for plate in s_.plates:       # MIMTM.1 / .10: no metal4 (so no via3) near a bottom plate
            cv.block(["metal4"], plate.grown(keep), "#mim")
        return s_.y1

    for d in [d for d in caps if shared not in d.nodes]:
        y = stack([d], y) + CAP_GAP
    st.y = y
    for d in devs:
        if d.kind == "r":
            rw = lt.width("resistor")
            length = resistor_length(lt, design.tech, d.value, rw)
            hd = resistor_heads(lt)
            e = lt.nm("pplus.enclosure.resistor")
            r = poly_resistor(cv, lt, x_left, st.y + e + hd, rw, length, d.nodes[0], d.nodes[1])
            st.term(d.nodes[0], "metal1", r["bottom"])
            st.term(d.nodes[1], "metal1", r["top"])
            st.y = r["extent"].y1 + GROUP_GAP
    # the op-amp's devices: N strips and a substrate tap, then P strips in their well
    opn = [d for d in devs if d.kind == "n" and not d.name.startswith("XS")]
    opp = [d for d in devs if d.kind == "p" and not d.name.startswith("XS")]
    swn = [d for d in devs if d.kind == "n" and d.name.startswith("XS")]
    swp = [d for d in devs if d.kind == "p" and d.name.startswith("XS")]
    _n_group(st, lt, opn, fit)
    st.y += GROUP_GAP
    _p_group(st, lt, opp, fit)
    st.y += GROUP_GAP
    # the shared lines, on the router's grid rows
    line_y = {}
    gy0 = half + pad_side(lt, "metal4") // 2
    j = -(-(st.y - gy0) // router_pitch)
    for net in LINES:
        yl = gy0 + j * router_pitch
        w = pad_side(lt, "metal3")
        b = cv.add("metal3", box(0, yl - w // 2, width, yl - w // 2 + w), net)
        st.term(net, "metal3", b)
        cv.label("metal3_label", w, yl, net)
        line_y[net] = yl
        j += 1
    st.y = gy0 + j * router_pitch + GROUP_GAP
    plan_n = _switch_plan(swn, fit, "vss", None)
    _n_group(st, lt, plan_n, fit)
    st.y += GROUP_GAP
    _p_group(st, lt, _switch_plan(swp, fit, _plan_end(plan_n, fit), "vdd"), fit)
    # the input capacitors, their top plates the shared node (C13 lowest)
    y = stack([d for d in caps if shared in d.nodes][::-1], st.y + GROUP_GAP)
    height = lt.snap_up(y + stub + lt.space("metal4"))
    # top edge: the column's out (= in) and nbias arrive on metal4
    for net, x in (("in", x_in), ("nbias", x_pass)):
        b = track(cv, lt, net, "metal4", x, height - stub, height)
        st.term(net, "metal4", b)
        cv.label("metal4_label", x, height - stub // 2, net)
    cv.add("boundary", box(0, 0, width, height), "")
    # route every net with two or more terminals
    area = box(half, half, width - half, height - half)
    r = GridRouter(cv, lt, ("metal2", "metal3", "metal4"), area, router_pitch, guards=GUARDED)
    for net, ts in st.terms.items():
        r.add_net(net, ts)
    r.route(sorted(st.terms, key=lambda n: (n not in GUARDED, -len(st.terms[n]))))   # guarded, then the busiest
    cv.ports = {"width": width, "height": height, "lines": line_y, "bottom": bottom_x,
                "top": {"in": x_in, "nbias": x_pass}}
    return cv


def _shared_node(caps) -> str:
    count = {}
    for d in caps:
        for n in d.nodes:
            count[n] = count.get(n, 0) + 1
    best = max(count, key=lambda n: count[n])
    return best if count[best] > 1 else ""


def _pads(dev: Device, fit, flip: bool) -> list:
    """The source / drain nets of a drawn device, bottom first."""
    nets = _finger_nets(dev, fit["fingers"][dev.name][0])[::2]
    return nets[::-1] if flip else nets


def _plan_end(plan, fit) -> str | None:
    return _pads(plan[-1][0], fit, plan[-1][1])[-1] if plan else None


def _switch_plan(devs, fit, below: str | None, above: str | None) -> list:
    """[(device, flipped)] bottom first: the order and orientation of a group of switch strips in which
    the fewest source / drain pads of two neighbouring strips put a floating node (``GUARDED``) next to
    a node that moves between the phases (a pad of another net that is neither guarded nor a line
    every column shares); ``below`` / ``above``: the net beyond the group's ends (a tap, the other
    group); then the fewest floating-node pads facing a pad of another net rather than a tap; then the
    fewest moving-node pads two pads from a floating node's (a pad of neither net between). Ties
    go to the drawn order, so a group with no floating node is drawn as listed."""
    from itertools import permutations, product

    def harm(a, b) -> int:
        if a is None or b is None or a == b:
            return 0
        quiet = set(GUARDED) | set(LINES)
        return int((a in GUARDED and b not in quiet) or (b in GUARDED and a not in quiet))

    def cost(plan):
        seq, flat = [below], [below]
        for d, f in plan:
            p = _pads(d, fit, f)
            seq += [p[0], p[-1]]
            flat += p
        seq.append(above)
        flat.append(above)
        pairs = list(zip(seq[::2], seq[1::2]))
        return (sum(harm(a, b) for a, b in pairs),
                sum(1 for a, b in pairs if None not in (a, b) and a != b and not {a, b} & TAPS
                    and (a in GUARDED or b in GUARDED)),
                sum(harm(a, c) for a, b, c in zip(flat, flat[1:], flat[2:]) if b not in (a, c)))

    if len(devs) > 6:    # 6! x 2^6 plans at most
        return [(d, False) for d in devs]
    best = None
    for order in permutations(devs):
        for flips in product((False, True), repeat=len(devs)):
            plan = list(zip(order, flips))
            c = cost(plan)
            if best is None or c < best[0]:
                best = (c, plan)
    return best[1]


def _n_group(st: Stack, lt, plan, fit) -> None:
    if not plan:
        return
    st.tap("p", "vss")
    for item in plan:
        d, flip = item if isinstance(item, tuple) else (item, False)
        st.y += STRIP_GAP
        n, wf = fit["fingers"][d.name]
        st.strip(d, n, wf, "n", flip)


def _p_group(st: Stack, lt, plan, fit) -> None:
    if not plan:
        return
    st.prev = None
    st.y += lt.nm("nwell.enclosure.pcomp") - lt.nm("pplus.enclosure.active")
    comps = []
    for i, item in enumerate(plan):
        d, flip = item if isinstance(item, tuple) else (item, False)
        if i:
            st.y += STRIP_GAP
        n, wf = fit["fingers"][d.name]
        comps.append(st.strip(d, n, wf, "p", flip).comp)
    st.y += STRIP_GAP
    comps.append(st.tap("n", "vdd"))
    nw = well(st.cv, lt, comps, "vdd")
    st.y = nw.y1


__all__ = ["afe_layout", "afe_devices", "cap_plate", "cap_width", "LINES"]
