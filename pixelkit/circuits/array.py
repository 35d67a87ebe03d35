"""Arrays of integrated dual pixels, up to the chip's 27 x 50 primary + 27 x 150 secondary.

Two forms:

- ``pixel_array(design, rows, cols)``: the array as one subcircuit of ``dualpix`` cells
  (ports ``vdd vpdr vrst ec_p tg_p ec_s tg_s``, per row ``rs_p_r rst_p_r rs_s_r rst_s_r``,
  per column ``col_p_c`` and ``col_s_j``, j = N c + k); the golden cell ``array_2x2``.
- ``array_bench(design, iph_p, iph_s, tile=...)``: a deck of one frame of an array - or
  of a :class:`Tile` of it (some arrays, rows and columns) - with the global-shutter
  sequence, the column loads and, ``with_afe``, each column's S1X/S2X samplers and SC
  AFE. Every subpixel is instantiated directly, so a tile is the same circuit as the
  corresponding part of the whole frame: row ``r`` is read at its own time of the
  frame (the full-frame timing), and a tile stops when its last row is read.
- ``handoff``: a tile of one row that starts from the column state another deck left at
  the row's start (:class:`Handoff`, see ``chip/frame.py``: the column chains).

Each column has its own load bias generator (an ideal reference current into a
diode-connected NMOS): columns then share only ideal supplies and row lines, so any
group of columns simulates as it does in the whole array. (One bias node per array
couples the columns through the loads' Cgd while they slew: 0.1 - 0.16 mV between two
arrays sharing one, measured under issue 14.)

Photocurrents are per subpixel: ``iph_p[r][c]`` (rows x cols) and ``iph_s[r][j]``
(rows x N cols), in A.
"""
from __future__ import annotations

import zlib
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..errors import ConfigError
from ..spice.netlist import Element, Model, Param, Pwl, Subckt
from ..tech.modellib import Include
from . import column
from .devices import mosfet

KINDS = ("primary", "secondary")
PREFIX = {"primary": "p", "secondary": "s"}
#: ``.param sw_stat_mismatch=1`` after the model library: the GF180 models' own
#: per-instance mismatch (Pelgrom: ``par_vth``, ``par_k`` in ``sm141064.ngspice``).
MISMATCH_INCLUDE = Include("include", Path(__file__).resolve().parent / "stat", "mismatch_on.spice", "")


def array_ports(design, rows: int, cols: int) -> tuple:
    n = design.secondary_per_pixel
    rows_ = [f"{k}_{r}" for r in range(rows) for k in ("rs_p", "rst_p", "rs_s", "rst_s")]
    return ("vdd", "vpdr", "vrst", "ec_p", "tg_p", "ec_s", "tg_s", *rows_,
            *(f"col_p_{c}" for c in range(cols)), *(f"col_s_{j}" for j in range(n * cols)))


def pixel_array(design, rows: int, cols: int) -> Subckt:
    if rows < 1 or cols < 1:
        raise ValueError("an array needs at least one row and one column")
    n = design.secondary_per_pixel
    elems, params = [], []
    for r in range(rows):
        for c in range(cols):
            sec_cols = [f"col_s_{n * c + k}" for k in range(n)]
            p = [("iph_p", Param(f"iph_p_{r}_{c}"))]
            p += [(f"iph_s{k}", Param(f"iph_s_{r}_{n * c + k}")) for k in range(n)]
            elems.append(Element(f"Xpix_{r}_{c}", ("vdd", "vpdr", "vrst", "ec_p", "tg_p", f"rst_p_{r}",
                                                   f"rs_p_{r}", f"col_p_{c}", "ec_s", "tg_s", f"rst_s_{r}",
                                                   f"rs_s_{r}", *sec_cols), "dualpix", tuple(p)))
            params.append((f"iph_p_{r}_{c}", 0.0))
            params += [(f"iph_s_{r}_{n * c + k}", 0.0) for k in range(n)]
    return Subckt(f"pixarray_{rows}x{cols}", array_ports(design, rows, cols), tuple(elems), tuple(params))


@dataclass(frozen=True)
class Tile:
    """A part of a frame: the arrays ``kinds``, the rows ``rows`` and the dual-pixel columns
    ``cols`` (secondary columns N c .. N c + N - 1 of each)."""
    kinds: tuple
    rows: tuple
    cols: tuple

    def columns(self, kind: str, n: int) -> list[int]:
        return list(self.cols) if kind == "primary" else [n * c + k for c in self.cols for k in range(n)]


#: The hold switches of a hand-over: 1 Ohm closed, 1e18 Ohm open (leaks < 4e-18 A at 3.3 V,
#: < 1e-11 V on C11 over a row); no hysteresis.
HOLD_SWITCH = Model("hold_sw", "sw", (("vt", 0.5), ("vh", 0.0), ("ron", 1.0), ("roff", 1e18)))
#: The hold releases over this ramp, ending at ``Handoff.t`` (the switch opens mid-ramp); at
#: least 1e-10 of ``t`` so that the deck's 12 significant digits keep the two corners apart.
HOLD_RELEASE = 1e-12


@dataclass(frozen=True)
class Handoff:
    """Column state handed from one deck to the next: until ``t`` each node in ``values``
    ((node, V) or (node, ((t, V), ...)), ...) is held at its value (or waveform) through a
    switch, which then opens; from ``t`` on the deck runs free from the state the previous
    deck had at ``t``."""
    t: float
    values: tuple

    def elements(self) -> list:
        ctl = Pwl(((0.0, 1.0), (self.t - max(HOLD_RELEASE, 1e-10 * self.t), 1.0), (self.t, 0.0)))
        out = [Element("Vhold", ("hold_ctl", "0"), ctl)]
        for i, (node, v) in enumerate(self.values):
            out += [Element(f"Vheld{i}", (f"held_{i}", "0"), Pwl(v) if isinstance(v, tuple) else float(v)),
                    Element(f"Shold{i}", (node, f"held_{i}", "hold_ctl", "0"), "hold_sw")]
        return out


def state_nodes(design, kind: str, j: int, with_afe: bool, absent_rows: bool = True) -> list[str]:
    """The nodes of column ``j`` of ``kind`` that carry its state from one row to the next:
    the column line, its bias and off-switch nodes and, with the AFE, the sampler output and
    the AFE's floating and op-amp state nodes (the macromodel's output is its pole node's
    ideal copy, so that node, not the output, is held). ``absent_rows``: the deck stands the
    other rows' RS switches in as one device (its floating drain node is held too)."""
    col = f"col_{PREFIX[kind]}_{j}"
    nodes = [col, f"nbias_{col}", *([f"sfo_off_{col}"] if absent_rows else [])]
    if with_afe:
        afe = f"xafe_{col}"
        nodes += [f"in_{col}", f"{afe}.vm", f"{afe}.x", f"{afe}.c"]
        if design.afe.opamp == "macro":
            nodes.append(f"{afe}.xop.n1")
        else:
            nodes += [f"out_{col}", *(f"{afe}.xop.{n}" for n in ("n1", "n2", "tail", "nb", "nz"))]
    return nodes


def frame_shape(design, iph_p, iph_s) -> tuple[int, int]:
    """(rows, cols) of the photocurrent maps; a ConfigError when they do not fit the chip."""
    ip, is_ = np.asarray(iph_p, float), np.asarray(iph_s, float)
    n = design.secondary_per_pixel
    if ip.ndim != 2 or ip.size == 0:
        raise ConfigError("array", "iph_primary_A", ip.shape, "a rows x cols map")
    rows, cols = ip.shape
    if is_.shape != (rows, n * cols):
        raise ConfigError("array", "iph_secondary_A", is_.shape, f"a {rows} x {n * cols} map")
    if rows > design.primary.rows or cols > design.primary.cols:
        raise ConfigError(design.source, "array size", f"{rows} x {cols}",
                          f"at most the chip's {design.primary.rows} x {design.primary.cols}")
    if not (np.all(np.isfinite(ip)) and np.all(np.isfinite(is_))) or ip.min() < 0 or is_.min() < 0:
        raise ConfigError("array", "photocurrent", "negative or not finite", "finite currents >= 0 A")
    return rows, cols


def whole(rows: int, cols: int) -> Tile:
    return Tile(KINDS, tuple(range(rows)), tuple(range(cols)))


def tile_seed(seed: int, tile: Tile) -> int:
    """The ngspice seed of one deck of a Monte Carlo frame (a frame is one deck per array, so
    each array's devices are drawn once, from their own seed)."""
    return zlib.crc32(f"{seed}:{tile.kinds}:{tile.rows}:{tile.cols}".encode()) % 2_000_000_000 + 1


def afe_caps(design, seed: int | None, kind: str, j: int) -> tuple:
    """(c11, c12, c13) of the AFE of column ``j`` of ``kind``: the design's, or drawn.

    Monte Carlo: each capacitor ~ N(C, (A_C / sqrt(C / C_density)) C), the technology's
    capacitor matching (``mismatch.cap_pelgrom``, ``mismatch.cap_density``), seeded by
    (seed, kind, column) so a column draws the same values in every tile.
    """
    a = design.afe
    nominal = (a.c11, a.c12, a.c13)
    if seed is None:
        return nominal
    from ..physics.pelgrom import cap_sigma_rel
    rng = np.random.default_rng([seed, KINDS.index(kind), j])
    return tuple(float(c * (1 + cap_sigma_rel(design, c) * rng.standard_normal())) for c in nominal)


def frame_timings(design, t_exp: float, rows: int) -> dict:
    """The frame's GS timing: EC holds the PDs in reset while the rows wait to be read
    (anti-blooming). Without it a bright PD keeps integrating through the storage time, goes
    into forward bias and spills onto FD, and ngspice stops ("timestep too small")."""
    from .testbench import timings
    return timings(design, t_exp, rows, ec_hold=True)


def array_bench(design, iph_p, iph_s, tile: Tile | None = None, t_exp: float | None = None,
                with_afe: bool = False, mismatch_seed: int | None = None, max_step: float | None = None,
                title: str = "array_bench", handoff: Handoff | None = None, tm: dict | None = None,
                compression: dict | None = None):
    """A frame (or a tile of it) read row by row; see the module docstring. ``tm``: the frame's
    timings, when not ``frame_timings`` (a long-S1 reference read, ``chip.settling``);
    ``compression``: per array, t_int / t_exp of currents that carry the charge of ``t_int``
    in the window (``chip.scene``): the light drops to current / compression when the exposure
    ends (``pixel5t(compressed=True)``)."""
    from .opamp import opamp
    from .afe import sc_afe
    from .pixel5t import pixel5t
    from .testbench import _deck, _options, _tran, controls, precharge_clock, sample_clocks, supplies
    rows, cols = frame_shape(design, iph_p, iph_s)
    ip, is_ = np.asarray(iph_p, float), np.asarray(iph_s, float)
    tile = tile or whole(rows, cols)
    n = design.secondary_per_pixel
    t_exp = design.experiment.t_window if t_exp is None else t_exp
    tm = tm or frame_timings(design, t_exp, rows)
    sim_rows = tile.rows
    el = [*supplies(design), *controls(design, tm, sim_rows, True, tile.kinds)]
    subckts = []
    if with_afe:
        el.append(Element("Vref", ("vref", "0"), design.afe.vref))
        subckts += [opamp(design), sc_afe(design)]
    for kind in tile.kinds:
        s, cur = PREFIX[kind], (ip if kind == "primary" else is_)
        comp = float((compression or {}).get(kind, 1.0))
        subckts.append(pixel5t(design, kind, compressed=comp != 1.0))
        if comp != 1.0:
            t = tm[kind]
            el.append(Element(f"Vexpo_{s}", (f"expo_{s}", "0"),
                              Pwl(((0.0, 1.0), (t.t_tx, 1.0), (t.t_tx + t.edge, 0.0)))))
        if with_afe:
            el += sample_clocks(design, tm[kind], s, sim_rows)
        el += precharge_clock(design, tm[kind], s, sim_rows)
        for j in tile.columns(kind, n):
            col = f"col_{s}_{j}"
            for r in sim_rows:
                ports = ("vdd", "vpdr", "vrst", f"ec_{s}", f"tg_{s}", f"rst_{s}_{r}", f"rs_{s}_{r}", col)
                i = float(cur[r][j])
                if comp == 1.0:
                    el.append(Element(f"X{s}_{r}_{j}", ports, f"pix5t_{kind}", (("iph", i),)))
                else:
                    el.append(Element(f"X{s}_{r}_{j}", (*ports, f"expo_{s}"), f"pix5t_{kind}_c",
                                      (("iph_read", i / comp), ("iph_exp", i - i / comp))))
            absent = rows - len(sim_rows)
            if absent:  # the other rows' RS switches (off) load the column: one device, m = their count
                dev = design.pixel.devices
                rs = mosfet(f"rsoff_{col}", f"sfo_off_{col}", "0", col, "0", dev.rs_w, dev.rs_l, design.tech)
                el.append(replace(rs, params=(*rs.params, ("m", absent))))
            # post-layout: each simulated row's share of the line's couplings to its row lines, the
            # global lines, the supplies and ground (``column.row_share``: what the dual-pixel bench's
            # ``dualpix`` holds); the lumped rest of the line (the other rows') then counts one row fewer
            # for every simulated row past the first
            line = "col_p" if kind == "primary" else f"col_s{j % n}"
            extra = (len(sim_rows) - 1) * column.row_share_total(design, line)
            ld = column.load(design, col, f"nbias_{col}")
            if extra:
                if ld[1].value - extra <= 0:
                    raise ValueError(f"{col}: the simulated rows' share of the line exceeds its lumped capacitance")
                ld = (ld[0], replace(ld[1], value=ld[1].value - extra))
            el += [*column.bias(design, f"nbias_{col}"), *ld]
            for r in sim_rows:
                nets = {"vdd": "vdd", "vpdr": "vpdr", "vrst": "vrst"}
                for kk in tile.kinds:
                    q = PREFIX[kk]
                    nets.update({f"ec_{q}": f"ec_{q}", f"tg_{q}": f"tg_{q}", f"rst_{q}": f"rst_{q}_{r}",
                                 f"rs_{q}": f"rs_{q}_{r}"})
                el += column.row_share(design, {line: col}, nets, str(r))
            if tm[kind].precharged:
                el += column.precharge(design, col, f"pre_{s}")
            if with_afe:
                el += column.sampler(design, col, f"in_{col}", f"s1_{s}", f"s2_{s}")
                caps = afe_caps(design, mismatch_seed, kind, j)
                el.append(Element(f"Xafe_{col}", (f"in_{col}", f"out_{col}", "vref", f"p1_{s}", f"p1_{s}b",
                                                  f"p2_{s}", f"p2_{s}b", "vdd"), "scafe",
                                  tuple(zip(("c11", "c12", "c13"), caps)) if mismatch_seed is not None else ()))
    if set(tile.kinds) == {"primary", "secondary"}:     # post-layout: column-to-column couplings per dual pixel
        for c in tile.columns("primary", n):
            lines = {"col_p": f"col_p_{c}", **{f"col_s{k}": f"col_s_{n * c + k}" for k in range(n)
                                             if n * c + k in tile.columns("secondary", n)}}
            el += column.line_couplings(design, lines, whole=True)
    last = max(tile.rows)
    stop = max(tm[k].row_end(last) + 0.05 * tm[k].t_row for k in tile.kinds)
    tran = replace(_tran(tm), stop=stop)
    if max_step is not None:
        tran = replace(tran, max_step=max_step)
    net = _deck(design, title, el, subckts, tran, options=_options(tm))
    if handoff is not None:
        net = replace(net, elements=(*net.elements, *handoff.elements()), models=(*net.models, HOLD_SWITCH))
    if mismatch_seed is not None:
        net = replace(net, includes=(*net.includes, MISMATCH_INCLUDE),
                      options=(*net.options, ("seed", tile_seed(mismatch_seed, tile))))
    return net
