"""The row driver of the boosted gate rail drawn from its netlist (``circuits.rowdriver``): cell
``ROWDRV``, one per driven gate line, the cells of a chip side by side in a bank above the array's
left margin (:mod:`.chip`).

A narrow, tall cell, stacked along y like the AFE (:mod:`.afe`'s ``Stack``). From the bottom
edge (facing the array) up:

- the output ``out`` as a metal4 stub at the bottom edge (the chip's strap to the line lands on it);
- a P+ substrate tap and the N devices, one strip each (the input inverter's, the level shifter's
  pair, the output inverter's);
- the lines every driver of the bank shares (abutting cells join them): ``vss vdd vgate``;
- the input inverter's P device in an n-well on ``vdd`` with its N+ tap;
- at the n-wells' different-potential spacing, the rail's n-well on ``vgate``: the shifter's
  cross-coupled P pair and the output inverter's P device, and its N+ tap;
- the input ``in`` as a metal4 stub at the top edge (a pin of the chip).

Every net is then routed by :mod:`.gridroute` on metal2 - metal4, as in the AFE.
"""
from __future__ import annotations

from .afe import GROUP_GAP, STRIP_GAP, Device, Stack
from .canvas import Canvas, box
from .gridroute import GridRouter
from .primitives import fold, pad_side, well
from .route import track
from .rules import RuleError

CELL = "ROWDRV"
WIDTH = 9000            # nm: the cell's width (the bank's pitch)
LINES = ("vss", "vdd", "vgate")
N_DEVICES = ("ni", "n1", "n2", "no")
P_SUPPLY = ("pi",)                  # in the n-well on vdd
P_RAIL = ("p1", "p2", "po")         # in the n-well on vgate


def driver_devices(design) -> list[Device]:
    """The driver's devices as the layout draws them (the subcircuit's own elements)."""
    from ..circuits.rowdriver import row_driver
    t = design.tech
    out = []
    for e in row_driver(design).elements:
        p = dict(e.params)
        out.append(Device(e.name[1:], "n" if e.value == t.mos.nmos else "p",
                          tuple("vss" if n == "0" else n for n in e.nodes), p["w"], p["l"]))
    return out


def row_driver_layout(design, lt) -> Canvas:
    """The ``ROWDRV`` cell: ports {"width", "height", "lines": {net: y}, "out": x, "in": x}. The
    strips' left edge is moved along x in steps of the grid until every net routes (the first
    position whose pads the router's grid reaches)."""
    from .route import RouteError
    x0 = lt.snap_up(lt.space("nwell") // 2 + lt.nm("nwell.enclosure.pcomp"))
    err = None
    for shift in range(0, 1000, 50):
        try:
            return _draw(design, lt, x0 + lt.snap(shift))
        except RouteError as e:
            err = e
    raise err


def _draw(design, lt, x_left: int) -> Canvas:
    devs = {d.name: d for d in driver_devices(design)}
    cv = Canvas(CELL, lt)
    wmax = ((WIDTH - 2 * 1200 - 2000) // lt.grid) * lt.grid
    fingers = {}
    for name, d in devs.items():
        got = fold(lt, round(d.w * 1e9), wmax)
        if got is None:
            raise RuleError("rowdriver_fit", f"{CELL} cell", f"{name} (W {d.w * 1e6:g} um) does not fold into "
                            f"fingers of at most {wmax / 1000:g} um", "pixel.gate_drive", design.pixel.gate_drive)
        fingers[name] = got
    st = Stack(cv, lt, x_left, 0)
    pitch = pad_side(lt, "metal4") + lt.space("metal4")
    half = max(lt.space(m) for m in ("metal2", "metal3", "metal4")) // 2
    g0 = half + pad_side(lt, "metal4") // 2
    x_out, x_in = g0 + 2 * pitch, g0 + 4 * pitch
    stub = lt.snap_up(pad_side(lt, "metal4") + lt.space("metal4"))
    b = track(cv, lt, "out", "metal4", x_out, 0, stub)
    st.term("out", "metal4", b)
    cv.label("metal4_label", x_out, stub // 2, "out")
    st.y = stub + GROUP_GAP
    st.tap("p", "vss")
    for name in N_DEVICES:
        st.y += STRIP_GAP
        st.strip(devs[name], *fingers[name], "n")
    st.y += GROUP_GAP
    line_y = {}
    j = -(-(st.y - g0) // pitch)
    for net in LINES:
        yl = g0 + j * pitch
        w = pad_side(lt, "metal3")
        st.term(net, "metal3", cv.add("metal3", box(0, yl - w // 2, WIDTH, yl - w // 2 + w), net))
        cv.label("metal3_label", w, yl, net)
        line_y[net] = yl
        j += 1
    st.y = g0 + j * pitch + GROUP_GAP
    for names, supply in ((P_SUPPLY, "vdd"), (P_RAIL, "vgate")):
        st.prev = None
        st.y += lt.nm("nwell.enclosure.pcomp") - lt.nm("pplus.enclosure.active")
        comps = []
        for i, name in enumerate(names):
            if i:
                st.y += STRIP_GAP
            comps.append(st.strip(devs[name], *fingers[name], "p").comp)
        st.y += STRIP_GAP
        comps.append(st.tap("n", supply))
        nw = well(cv, lt, comps, supply)
        st.y = nw.y1 + lt.space("nwell")     # NW.2b: wells of different potential
    height = lt.snap_up(st.y + stub)
    b = track(cv, lt, "in", "metal4", x_in, height - stub, height)
    st.term("in", "metal4", b)
    cv.label("metal4_label", x_in, height - stub // 2, "in")
    cv.add("boundary", box(0, 0, WIDTH, height), "")
    r = GridRouter(cv, lt, ("metal2", "metal3", "metal4"), box(half, half, WIDTH - half, height - half), pitch)
    for net, ts in st.terms.items():
        r.add_net(net, ts)
    r.route(sorted(st.terms, key=lambda n: (n in LINES, -len(st.terms[n]))))   # the signals, then the supplies
    cv.ports = {"width": WIDTH, "height": height, "lines": line_y, "out": x_out, "in": x_in, "stub": stub}
    return cv


__all__ = ["row_driver_layout", "driver_devices", "CELL", "WIDTH"]
