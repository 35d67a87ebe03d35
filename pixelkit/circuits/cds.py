"""Role benches: any :class:`~pixelkit.circuits.roles.PixelCell` read by its column with true CDS.

One pixel on its column line: the source-follower load (an NMOS mirror of ``column.bias``), the
line's capacitance, and two sample-and-hold switches (NMOS, gates ``shr`` / ``shs``) onto
``column.sh_cap`` each: SHR holds the reset level, SHS the signal level of the same read
(``physics.cdstiming``). The pixel's ports are driven by role: the supply, the reset drain, RS, RST,
TG, SHR / SHS, bias ports at their fixed voltages, and the light port in nA.

A bench runs one or more *frames* back to back, each ``(photocurrent A, exposure s)``: shutter,
exposure, read. ``cds(result, frame)`` of ``measure.cds`` reads each frame's CDS output. Every
frame after the first starts from the state the one before left (a lag frame follows a bright one
in the same deck).
"""
from __future__ import annotations

from ..physics.cdstiming import CdsTiming
from ..spice.netlist import Element, Netlist, Pwl, Tran
from .devices import mosfet, photodiode_model
from .ppd import LIGHT_SCALE
from .roles import CDS_ROLES as CDS_NEEDS
from .testbench import waveform

#: Nets of the bench, by role.
NETS = {"vdd": "vdd", "vrst": "vrst", "rst": "rst", "tg": "tg", "rs": "rs", "col": "col"}


def gate_high(design) -> float:
    """RST's (and by default TG's) high level: the supply, or the boosted rail."""
    lv = design.levels
    return lv.v_gate if lv.gate_drive == "boosted" else design.tech.supply


def tg_high(design) -> float:
    lv = design.levels
    return gate_high(design) if lv.tg_high is None else lv.tg_high


def timing_of(design) -> CdsTiming:
    t = design.timing
    return CdsTiming(t_rst=t.t_rst, t_tg=t.t_tg, t_sh=t.t_sh, t_settle=t.t_settle, edge=t.edge)


def frame_starts(design, exposures) -> list[float]:
    """Absolute start time of each frame."""
    tm, out, t0 = timing_of(design), [], 0.0
    for t_exp in exposures:
        out.append(t0)
        t0 += tm.frame(t_exp).length
    return out


def bias(design) -> tuple:
    """The loads' bias: the reference current into a diode-connected NMOS (node ``nbias``)."""
    c = design.column
    return (Element("Ibias", ("vdd", "nbias"), c.bias),
            mosfet("bias", "nbias", "nbias", "0", "0", c.load_w, c.load_l, design.tech))


def column(design, k: int) -> tuple:
    """Column ``k``: its load, line capacitance and S/H switches onto ``vshr<k>`` / ``vshs<k>``."""
    c, t, col = design.column, design.tech, f"col{k}"
    return (mosfet(f"ld{k}", col, "nbias", "0", "0", c.load_w, c.load_l, t),
            Element(f"Ccol{k}", (col, "0"), c.cap),
            mosfet(f"shr{k}", col, "shr", f"vshr{k}", "0", c.sw_w, c.sw_l, t),
            mosfet(f"shs{k}", col, "shs", f"vshs{k}", "0", c.sw_w, c.sw_l, t),
            Element(f"Cshr{k}", (f"vshr{k}", "0"), c.sh_cap), Element(f"Cshs{k}", (f"vshs{k}", "0"), c.sh_cap))


def supplies(design, cell) -> tuple:
    vdd = design.tech.supply
    out = [Element("Vdd", ("vdd", "0"), vdd)]
    if cell.port("vrst"):
        out.append(Element("Vrstd", ("vrst", "0"), design.levels.v_rst_for(vdd)))
    out += [Element(f"Vb_{p}", (f"b_{p}", "0"), v) for p, v in cell.bias]
    return tuple(out)


def nets(cell, k: int) -> dict:
    """Role -> bench net of column ``k``'s pixel; without a reset-drain role the reset drain is the supply."""
    return {**NETS, "col": f"col{k}", "vrst": "vrst" if cell.port("vrst") else "vdd"}


def controls(design, exposures, starts) -> tuple:
    """RS, RST, TG, SHR and SHS over every frame."""
    tm, e = timing_of(design), design.timing.edge
    g, vdd, lo, gt = gate_high(design), design.tech.supply, design.levels.tg_low, tg_high(design)
    iv = {k: [] for k in ("rs", "rst", "tg", "shr", "shs")}
    for t_exp, t0 in zip(exposures, starts):
        f = tm.frame(t_exp)
        iv["rst"].append((t0, t0 + tm.t_shutter))
        iv["tg"].append((t0 + tm.shutter_tg[0], t0 + tm.shutter_tg[1]))
        r = t0 + f.t_read
        iv["rs"].append((r, r + tm.t_row))
        for k, ph in (("rst", tm.rst), ("tg", tm.tg), ("shr", tm.shr), ("shs", tm.shs)):
            iv[k].append((r + ph[0], r + ph[1]))
    tg = waveform(iv["tg"], gt - lo, e)
    return (Element("Vrs", ("rs", "0"), waveform(iv["rs"], vdd, e)),
            Element("Vrst", ("rst", "0"), waveform(iv["rst"], g, e)),
            Element("Vtg", ("tg", "0"), Pwl(tuple((t, v + lo) for t, v in tg.points)) if lo else tg),
            Element("Vshr", ("shr", "0"), waveform(iv["shr"], vdd, e)),
            Element("Vshs", ("shs", "0"), waveform(iv["shs"], vdd, e)))


def light(design, k: int, currents, exposures, starts) -> Element:
    """Column ``k``'s light port: each frame's photocurrent (A, in nA on the port) during the frame's
    light window (``Frame.light``: shutter TG fall to read TG rise), dark outside it."""
    tm, e = timing_of(design), design.timing.edge
    pts = [(0.0, 0.0)]
    for i_ph, t_exp, t0 in zip(currents, exposures, starts):
        if i_ph:
            on, off = tm.frame(t_exp).light
            pts += [(t0 + on, 0.0), (t0 + on + e, i_ph / LIGHT_SCALE), (t0 + off - e, i_ph / LIGHT_SCALE), (t0 + off, 0.0)]
    return Element(f"Vlight{k}", (f"light{k}", "0"), Pwl(tuple(pts)) if len(pts) > 1 else 0.0)


def instance(cell, k: int) -> Element:
    return Element(f"X{k}", cell.connections(nets(cell, k), f"light{k}"), cell.subckt.name)


def deck(design, cell, elements, analysis, title: str, ic=(), saves=(), options=(), models=()) -> Netlist:
    t = design.tech
    return Netlist(title=title, elements=tuple(elements), analysis=analysis,
                   subckts=(*cell.support, cell.subckt),
                   models=(*photodiode_model(t, design.temperature), *cell.models, *models),
                   includes=t.models.includes(design.corner or None), ic=tuple(ic),
                   temperature_C=design.temperature - 273.15, saves=tuple(saves), options=tuple(options))


#: gmin of the role benches: FD and the S/H nodes float for a whole exposure.
OPTIONS = (("gmin", 1e-18),)


def cds_bench(design, cell, exposures, currents, title: str = "cds_bench", saves=None) -> Netlist:
    """Pixels of ``cell`` read with true CDS, one per column, frames back to back: ``exposures`` (s) per
    frame, ``currents[k]`` the photocurrent (A) of column ``k``'s pixel in each frame. The pixels start
    from their operating point with the gates low (a pinned photodiode then sits at its dark
    equilibrium, full): callers that measure a first frame put a flush frame before it."""
    from ..errors import ConfigError
    cell.require(CDS_NEEDS, "a true-CDS read")
    exposures = [float(t) for t in exposures]
    currents = [[float(i) for i in row] for row in currents]
    if any(len(row) != len(exposures) for row in currents):
        raise ValueError("one photocurrent per frame for every column")
    tm = timing_of(design)
    for t_exp in exposures:
        lo = tm.frame(t_exp).min_exposure
        if t_exp < lo:
            raise ConfigError(design.source, "exposure", t_exp, f"at least {lo:g} s (the read starts after the shutter)")
    starts = frame_starts(design, exposures)
    stop = starts[-1] + tm.frame(exposures[-1]).length
    el = [*supplies(design, cell), *controls(design, exposures, starts), *bias(design)]
    for k, row in enumerate(currents):
        el += [light(design, k, row, exposures, starts), instance(cell, k), *column(design, k)]
    if saves is None:   # both samples of every column, and pixel 0's column and probes
        saves = [*(n for k in range(len(currents)) for n in (f"vshr{k}", f"vshs{k}")), "col0",
                 *(f"x0.{n}" for _r, n in cell.probes)]
    net = deck(design, cell, el, Tran(1e-9, stop, 0.0, tm.t_row / 4, uic=True), title, saves=saves, options=OPTIONS)
    net.meta["what"] = (f"{len(currents)} pixel(s) {cell.subckt.name} read with true CDS over {len(exposures)} "
                        f"frame(s) of {', '.join(f'{t * 1e6:.4g}' for t in exposures)} us")
    net.meta["frames"] = {"exposures": exposures, "starts": starts}
    return net
