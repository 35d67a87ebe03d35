"""Power: supply current per block measured in SPICE over a frame, and an analytic estimate.

The bench is one row of one column of each array with its AFE (``circuits.array.array_bench``,
as the chip's netlist builds a column: its own bias generator, load, samplers and AFE), with
every block on a supply of its own:

- ``reset``: the reset drains (``Vpdr``, ``Vrstd``): the charge that resets the PDs and FDs;
- ``read``: the pixels' SF drains (``vdd`` of the subpixels): the column current while a row
  is selected (the load's current comes through the selected pixel);
- ``bias``: the column's bias reference (``Ibias``);
- ``afe``: the AFE (``vdd`` of the SC cell: the OTA's own currents; the macromodel draws
  nothing, so the design's ``afe.supply_current`` stands for its quiescent current);
(The control sources are left out: the chip of [Thesis2019] took every control signal from an FPGA.)

From each supply's current: the static current (mean over the exposure, nothing switching)
and the energy above it of the frame's events (global reset and transfer) and of one row's
read. Over a frame of the design (``frame_period``: the longer exposure, the global-shutter
sequence and the slower array's readout of all its rows), per column:
P = V I_static + (rows (E_events + E_read)) / T_frame; the chip is the columns of both arrays.

Independent path (``estimate``): bias currents x supply: each column's load carries
``pixel.sf_bias`` while a row is read (rows t_row of every frame), its bias reference
``sf_bias`` always, its op-amp ``afe.supply_current`` always (the OTA: 7 x ``afe.ota_bias``, its mirror ratios);
the column line (``physics.noise.column_capacitance``) is charged to the reset level (FD
reset minus the SF's ~1.1 V) once per read, and with a column precharge (``timing.pre_on``)
the line and C11 once more, from ground (a lower bound there: the follower also drives the
precharge switch while both conduct, not estimated); the resets move the charge of a mid-scale
signal back onto the PD once per frame.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..circuits.opamp import OTA_MIRROR_SUM
from ..spice.netlist import Element

BLOCKS = ("reset", "read", "bias", "afe")


def frame_period(design) -> float:
    """Exposure (the longer one), the GS sequence before the read, and the slower array's readout."""
    from ..circuits.array import frame_timings
    tm = frame_timings(design, max(design.primary.t_int, design.secondary.t_int), 1)
    return max(t.t_read + getattr(design, k).rows / getattr(design, k).f_read for k, t in tm.items())


def _split(net, design):
    """The bench with every block on its own supply source."""
    vdd = design.tech.supply
    els = []
    for e in net.elements:
        name = e.name.lower()
        if isinstance(e.value, str) and e.value.startswith("pix5t_"):
            e = replace(e, nodes=tuple("vdd_read" if n == "vdd" else n for n in e.nodes))
        elif name.startswith("ibias"):
            e = replace(e, nodes=tuple("vdd_bias" if n == "vdd" else n for n in e.nodes))
        elif e.value == "scafe":
            e = replace(e, nodes=tuple("vdd_afe" if n == "vdd" else n for n in e.nodes))
            if design.afe.opamp == "macro" and design.afe.supply_current > 0:
                els.append(Element(f"Iq_{e.name}"[:64], ("vdd_afe", "0"), design.afe.supply_current))
        els.append(e)
    els += [Element(f"Vdd_{b}", (f"vdd_{b}", "0"), vdd) for b in ("read", "bias", "afe")]
    net = replace(net, elements=tuple(els))
    return replace(net, saves=tuple(f"i({s})" for names in _sources(design, net).values() for s in names))


def _sources(design, net) -> dict:
    """block -> [(source name, its voltage)]"""
    out = {b: [] for b in BLOCKS}
    for e in net.elements:
        n = e.name.lower()
        if n in ("vpdr", "vrstd"):
            out["reset"].append(n)
        elif n.startswith("vdd_"):
            out[n[4:]].append(n)
        elif n in ("vdd", "vref"):   # what is left on vdd (sampler bulks) and the AFE's reference
            out["afe"].append(n)
    return out


def _bench(design, kind: str, draw=None):
    from ..circuits.array import Tile, array_bench
    from ..chip.scene import default_stimulus
    from . import mismatch
    n = design.secondary_per_pixel
    stim = default_stimulus(design, design.experiment.t_window)
    net = array_bench(design, np.full((1, 1), stim["iph_p"]), np.full((1, n), stim["iph_s"]),
                      Tile((kind,), (0,), (0,)), with_afe=True, title=f"vfy_power_{kind[0]}")
    return mismatch.apply(_split(net, design), design, draw)


def _energies(r, net, design, kind: str) -> dict:
    """Per block: static current (A), energy of the frame's events and of one row read (J), at its V."""
    from ..circuits.array import frame_timings
    t = frame_timings(design, design.experiment.t_window, 1)[kind]
    time = r.time
    out = {}
    volts = {e.name.lower(): e.value for e in net.elements}
    for block, names in _sources(design, net).items():
        p = np.zeros_like(time)
        for s in names:
            p = p - volts[s] * r[f"i({s})"]     # power delivered by the source

        def energy(a, b, minus=0.0):
            m = (time > a) & (time < b)
            tt = np.concatenate([[a], time[m], [b]])
            return float(np.trapezoid(np.interp(tt, time, p) - minus, tt))
        a, b = t.t_start + 0.5e-6, t.t_tx - t.t_tg - t.t_gap - 0.1e-6   # nothing switches in between
        p_static = energy(a, b) / (b - a)
        out[block] = {"static_W": p_static, "events_J": energy(0.0, t.t_read, p_static),
                      "read_J": energy(t.t_read, t.row(1), p_static)}
    return out


def measure(design, draw=None, backend: str = "batch") -> dict:
    """Per-block power of each array's column and the chip at the design's frame rate (W)."""
    from ..spice import simulate_many
    from .copies import one_column
    single = one_column(design, draw)   # the N secondary columns are copies: one is simulated
    nets = {"primary": _bench(design, "primary", draw), "secondary": _bench(single or design, "secondary", draw)}
    res = dict(zip(nets, simulate_many(list(nets.values()), backend=backend, jobs=1)))
    t_frame = frame_period(design)
    n = design.secondary_per_pixel
    per_col, chip = {}, {b: 0.0 for b in BLOCKS}
    for kind, net in nets.items():
        sub = getattr(design, kind)
        cols_in_bench = 1 if kind == "primary" or single else n
        e = _energies(res[kind], net, design, kind)
        per_col[kind] = {b: (x["static_W"] + sub.rows * (x["events_J"] + x["read_J"]) / t_frame) / cols_in_bench
                         for b, x in e.items()}
        for b in BLOCKS:
            chip[b] += per_col[kind][b] * sub.cols
    pixel_W = sum(per_col["primary"][b] / design.primary.rows + n * per_col["secondary"][b] / design.secondary.rows
                  for b in ("reset", "read"))
    return {"frame_period_s": t_frame, "per_column_W": per_col, "chip_blocks_W": chip,
            "pixel_W": pixel_W, "column_W": per_col["primary"]["bias"] + per_col["primary"]["afe"],
            "chip_W": sum(chip.values()), "estimate": estimate(design)}


def estimate(design) -> dict:
    """Bias currents x supply x duty (the independent path; see the module docstring)."""
    from ..physics import noise
    from ..physics.subpixel import pd_node
    vdd, px, a = design.tech.supply, design.pixel, design.afe
    t_frame = frame_period(design)
    # the OTA: its reference, the tail (2x) and the output stage (4x)
    i_afe = a.supply_current if a.opamp == "macro" else OTA_MIRROR_SUM * a.ota_bias
    chip = {b: 0.0 for b in ("reset", "read", "bias", "afe")}
    for kind in ("primary", "secondary"):
        sub = getattr(design, kind)
        duty = sub.rows / sub.f_read / t_frame
        # the load's current while a row is read, and the column line charged once per read
        c_col = noise.column_capacitance(design)
        # a column precharge (timing.pre_on) grounds the line and C11 in S1: the follower charges
        # both back to the level once more per read
        c_read = c_col + (c_col + a.c11 if sub.timing.pre_on is not None else 0.0)
        chip["read"] += sub.cols * vdd * (px.sf_bias * duty + c_read * (px.v_fd_reset - 1.1) * sub.rows / t_frame)
        chip["bias"] += sub.cols * vdd * px.sf_bias
        chip["afe"] += sub.cols * vdd * i_afe
        node = pd_node(design, kind, parasitics=True)
        q = float(node.charge(px.v_pd_reset) - node.charge(px.v_pd_reset - 0.5 * px.swing))
        chip["reset"] += sub.cols * sub.rows * px.v_pd_reset * q / t_frame
    return {"chip_blocks_W": chip, "chip_W": sum(chip.values()), "frame_period_s": t_frame}
