"""Testbenches: circuits + supplies + control waveforms + analysis, as netlists.

- ``dual_pixel_bench``: one integrated pixel read through its column loads with
  the global-shutter sequence (optionally through S1X/S2X into the SC AFEs).
- ``afe_bench``: the SC AFE driven with (Vsig, Vrst) pairs, one pair per cycle.
- ``pd_pair_bench``: two bare photodiodes discharged from one bias (fig. A.1).
"""
from __future__ import annotations

from dataclasses import replace

from ..spice.netlist import Element, Netlist, Op, Pwl, Tran
from . import column
from .afe import sc_afe
from .devices import gate_high, mosfet, photodiode, photodiode_model
from .dual_pixel import dual_pixel
from .opamp import opamp
from ..physics.timing import GsTiming, timings  # noqa: F401 (timings: callers import it from here)


def waveform(intervals, high: float, edge: float, invert: bool = False) -> Pwl:
    """PWL that is ``high`` inside each (on, off) interval and 0 outside (or the reverse)."""
    lo, hi = (high, 0.0) if invert else (0.0, high)
    ivs = sorted(intervals)
    pts = [(0.0, hi if ivs and ivs[0][0] <= 0 else lo)]
    for on, off in ivs:
        if on > 0:
            pts += [(on, lo), (on + edge, hi)]
        pts += [(off, hi), (off + edge, lo)]
    return Pwl(tuple(pts))


def _deck(design, title, elements, subckts=(), analysis=None, ic=(), saves=(), options=()):
    t = design.tech
    return Netlist(title=title, elements=tuple(elements), analysis=analysis, subckts=tuple(subckts),
                   models=photodiode_model(t, design.temperature), includes=t.models.includes(design.corner or None),
                   ic=tuple(ic), temperature_C=design.temperature - 273.15, saves=tuple(saves),
                   options=tuple(options))


def real_timings(design, t_store: float = 0.0, ec_hold: bool | None = None) -> dict:
    """The design's own integration times (``primary.t_int``, ``secondary.t_int``)."""
    return timings(design, design.primary.t_int, 1, design.secondary.t_int, t_store, ec_hold)


#: Decks whose exposure is longer than this take large steps during the exposure.
LONG_EXPOSURE = 100e-6
#: gmin of long decks: 1e-18 S leaks 2e-18 A at 2 V, < 1 % of the smallest PD dark
#: current at 25 degC (the default 1e-15 S would leak ~3x the dark current).
LONG_OPTIONS = (("gmin", 1e-18),)


def _options(tm: dict) -> tuple:
    return LONG_OPTIONS if max(t.t_exp + t.t_store for t in tm.values()) > LONG_EXPOSURE else ()


def _tran(tm: dict) -> Tran:
    """Short decks: 20 ns max step (as the experiment). Long decks: the flat exposure is
    stepped by the simulator's error control, bounded to half the shorter row time (edges
    are PWL breakpoints, so the switching is still resolved): on the reference design's
    1 ms / 12 ms bench this is 20x faster than t_row / 20 and moves the double-sampled
    signals by 0.1 mV (``benchmarks/storage.py``)."""
    stop = max(t.t_stop for t in tm.values())
    longest = max(t.t_exp + t.t_store for t in tm.values())
    if longest <= LONG_EXPOSURE:
        return Tran(5e-9, stop, 0.0, 20e-9)
    return Tran(5e-9, stop, 0.0, min(t.t_row for t in tm.values()) / 2)


def supplies(design) -> tuple:
    px = design.pixel
    return (Element("Vdd", ("vdd", "0"), design.tech.supply), Element("Vpdr", ("vpdr", "0"), px.v_pd_reset),
            Element("Vrstd", ("vrst", "0"), px.v_fd_reset))


def controls(design, tm: dict, rows, row_lines: bool, kinds=("primary", "secondary")) -> list:
    """Control sources of the arrays ``kinds``. ``rows``: a count or the row indices to drive;
    ``row_lines``: per-row RS/RST names (arrays). EC, TG and RST go up to ``gate_high`` (the supply, or
    the boosted rail of ``pixel.gate_drive = "boosted"``); RS to the supply."""
    vdd, gate, out = design.tech.supply, gate_high(design), []
    for arr, s in (("primary", "p"), ("secondary", "s")):
        if arr not in kinds:
            continue
        t = tm[arr]
        out.append(Element(f"Vec_{s}", (f"ec_{s}", "0"), waveform(t.ec(), gate, t.edge)))
        out.append(Element(f"Vtg_{s}", (f"tg_{s}", "0"), waveform(t.tg(), gate, t.edge)))
        for r in t.row_list(rows):
            sfx = f"_{r}" if row_lines else ""
            out.append(Element(f"Vrst_{s}{sfx}", (f"rst_{s}{sfx}", "0"), waveform(t.rst(r), gate, t.edge)))
            out.append(Element(f"Vrs_{s}{sfx}", (f"rs_{s}{sfx}", "0"), waveform(t.rs(r), vdd, t.edge)))
    return out


def sample_clocks(design, t: GsTiming, prefix: str, rows: int) -> list:
    """S1/S2 and the AFE phases p1/p2 (with complements) of one array."""
    vdd, e, out = design.tech.supply, t.edge, []
    no = design.afe.nonoverlap
    # p1 opens ``no`` before S1X (its injection is then signal independent);
    # p2 closes ``no`` before S2X, so the loop is closed before the input moves.
    p1 = [(a, b - no) for a, b in t.s1(rows)]
    p2 = [(a - no, b) for a, b in t.s2(rows)]
    for name, iv in (("s1", t.s1(rows)), ("s2", t.s2(rows)), ("p1", p1), ("p2", p2)):
        out.append(Element(f"V{name}_{prefix}", (f"{name}_{prefix}", "0"), waveform(iv, vdd, e)))
        out.append(Element(f"V{name}b_{prefix}", (f"{name}_{prefix}b", "0"), waveform(iv, vdd, e, invert=True)))
    return out


def precharge_clock(design, t: GsTiming, prefix: str, rows) -> list:
    """The column precharge control of one array (none when its timing has no precharge)."""
    if not t.precharged:
        return []
    return [Element(f"Vpre_{prefix}", (f"pre_{prefix}", "0"), waveform(t.pre(rows), design.tech.supply, t.edge))]


def dual_pixel_bench(design, iph_p: float, iph_s, t_exp: float | None = None, with_afe: bool = False,
                     title: str = "dual_pixel_bench", tm: dict | None = None) -> Netlist:
    """One integrated pixel, its column loads, the GS sequence; ``iph_s`` per secondary.

    ``tm``: the timings (see ``timings``/``real_timings``); default both arrays exposed
    over ``t_exp`` (the experiment's window).
    """
    n = design.secondary_per_pixel
    iph_s = tuple(iph_s) if isinstance(iph_s, (tuple, list)) else (iph_s,) * n
    t_exp = design.experiment.t_window if t_exp is None else t_exp
    tm = tm or timings(design, t_exp)
    cols = ["col_p", *(f"col_s{k}" for k in range(n))]
    params = (("iph_p", iph_p), *((f"iph_s{k}", i) for k, i in enumerate(iph_s)))
    el = [*supplies(design), *controls(design, tm, 1, row_lines=False), *column.bias(design),
          Element("X1", ("vdd", "vpdr", "vrst", "ec_p", "tg_p", "rst_p", "rs_p", "col_p", "ec_s", "tg_s", "rst_s",
                         "rs_s", *cols[1:]), "dualpix", params)]
    for c in cols:
        el += column.load(design, c)
    el += column.line_couplings(design, {c: c for c in cols})
    for arr, s in (("primary", "p"), ("secondary", "s")):
        if tm[arr].precharged:
            el += precharge_clock(design, tm[arr], s, 1)
            el += [e for c in cols if (c == "col_p") == (s == "p") for e in column.precharge(design, c, f"pre_{s}")]
    subckts = list(dual_pixel(design))
    if with_afe:
        el.append(Element("Vref", ("vref", "0"), design.afe.vref))
        for arr, s in (("primary", "p"), ("secondary", "s")):
            el += sample_clocks(design, tm[arr], s, 1)
        for c in cols:
            s = "p" if c == "col_p" else "s"
            el += column.sampler(design, c, f"in_{c}", f"s1_{s}", f"s2_{s}")
            el.append(Element(f"Xafe_{c}", (f"in_{c}", f"out_{c}", "vref", f"p1_{s}", f"p1_{s}b",
                                            f"p2_{s}", f"p2_{s}b", "vdd"), "scafe"))
        subckts += [opamp(design), sc_afe(design)]
    net = _deck(design, title, el, subckts, _tran(tm), options=_options(tm))
    net.meta["what"] = (f"the dual-pixel bench{' with AFE' if with_afe else ''} of {design.name} at "
                        f"I_primary = {iph_p * 1e9:.4g} nA, I_secondary = {iph_s[0] * 1e12:.4g} pA")
    return net


def afe_bench(design, pairs, t_cycle: float | None = None, vos: float = 0.0,
              title: str = "afe_bench") -> Netlist:
    """The SC AFE fed (Vsig, Vrst) pairs: Vsig during p1, Vrst during p2 of each cycle."""
    t_cycle = t_cycle or 1.0 / design.afe.f_clk
    t = GsTiming(t_exp=0.0, t_row=t_cycle, rows=len(pairs), t_reset=0.0, t_tg=0.0, t_gap=0.0, t_pre=0.0)
    vdd, e = design.tech.supply, t.edge
    pts = [(0.0, pairs[0][0])]
    for r, (vsig, vrst) in enumerate(pairs):
        t0 = t.row(r)
        step = t.s2_window(r)[0]  # the input moves when S2X would connect it, loop closed
        pts += [(t0 + 0.02 * t_cycle, vsig), (step, vsig), (step + 2 * e, vrst), (t0 + 0.98 * t_cycle, vrst)]
    clean = [pts[0]] + [p for a, p in zip(pts, pts[1:]) if p[0] > a[0]]
    el = [Element("Vdd", ("vdd", "0"), vdd), Element("Vref", ("vref", "0"), design.afe.vref),
          Element("Vin", ("in", "0"), Pwl(tuple(clean))), *sample_clocks(design, t, "a", len(pairs)),
          Element("Xafe", ("in", "out", "vref", "p1_a", "p1_ab", "p2_a", "p2_ab", "vdd"), "scafe")]
    op = opamp(design)
    if vos:
        if design.afe.opamp != "macro":
            raise ValueError("an input offset can be set on the macromodel only")
        op = replace(op, params=(("vos", vos),))
    return _deck(design, title, el, (op, sc_afe(design)), Tran(5e-9, t.t_stop, 0.0, 20e-9))


def pd_pair_bench(design, i_primary: float, i_secondary: float, t_stop: float, v0: float,
                  title: str = "pd_pair_bench") -> Netlist:
    """Both bare PDs (fig. A.1) discharged from ``v0`` by constant currents."""
    t, p, s = design.tech, design.primary, design.secondary
    el = (photodiode("p", "pdp", p.area, p.perimeter, t), Element("Ip", ("pdp", "0"), i_primary),
          photodiode("s", "pds", s.area, s.perimeter, t), Element("Is", ("pds", "0"), i_secondary))
    net = _deck(design, title, el, (), Tran(t_stop / 500, t_stop, 0.0, t_stop / 500, uic=True),
                ic=(("pdp", v0), ("pds", v0)))
    net.meta["what"] = (f"the bare-PD pair of {design.name} (fig. A.1) at I = {i_primary * 1e9:.4g} nA / "
                        f"{i_secondary * 1e9:.4g} nA from {v0:g} V")
    return net


def read_chain(design) -> tuple:
    """One SF (gate ``fd``) with RS on, its column line ``col`` and load, and the supply."""
    dev, t, vdd = design.pixel.devices, design.tech, design.tech.supply
    return (Element("Vdd", ("vdd", "0"), vdd), Element("Vrs", ("rs", "0"), vdd),
            mosfet("sf", "vdd", "fd", "sfo", "0", dev.sf_w, dev.sf_l, t),
            mosfet("rs", "sfo", "rs", "col", "0", dev.rs_w, dev.rs_l, t),
            *column.bias(design), *column.load(design, "col"))


def sf_bench(design, v_fd: float, title: str = "sf_bench") -> Netlist:
    """Operating point of the read chain with the SF gate held at ``v_fd``."""
    return _deck(design, title, (*read_chain(design), Element("Vfd", ("fd", "0"), v_fd)), (), Op())


def dark_bench(design, which: str, t_int: float, title: str = "dark_bench") -> Netlist:
    """The PD node of ``which`` subpixel with its EC and TG (off), reset by EC then dark for ``t_int``.

    The PD's dark current comes from the diode card (the kit's one law at the deck
    temperature); the EC/TG junctions add what the BSIM4 models leak. gmin 1e-18.
    """
    sub, dev, t, px = getattr(design, which), design.pixel.devices, design.tech, design.pixel
    t_reset, edge = sub.timing.t_reset, sub.timing.edge
    el = (Element("Vpdr", ("vpdr", "0"), px.v_pd_reset), Element("Vfd", ("fd", "0"), px.v_fd_reset),
          Element("Vec", ("ec", "0"), waveform([(0.0, t_reset)], gate_high(design), edge)),
          Element("Vtg", ("tg", "0"), 0.0),
          photodiode("pd", "pd", sub.area, sub.perimeter, t),
          mosfet("ec", "vpdr", "ec", "pd", "0", dev.ec_w, dev.ec_l, t),
          mosfet("tg", "fd", "tg", "pd", "0", dev.tg_w, dev.tg_l, t))
    return _deck(design, title, el, (), Tran(1e-9, t_reset + t_int, 0.0, t_int / 200), options=LONG_OPTIONS)
