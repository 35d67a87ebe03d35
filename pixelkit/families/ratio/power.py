"""Power of the ratio pixel's array and column readout at the design's frame rate.

The bench is one pixel (two loops) with its column's four lines (precharge PMOS, clamp,
C_par, inverter) and a bias mirror (``circuit.ratio_bench``), every block on a supply of
its own:

- ``read``: the column lines (``vdd`` of the column cells): the two loops' tail currents of
  the selected row, whether they come through the precharge PMOS, the clamp or by
  discharging C_par, and the inverters' crowbar current while a line crosses their trip;
- ``bias``: the column's bias reference (``Ibias`` into the diode-connected mirror);
- ``photo``: the pixel's n-wells (``vdd`` of the pixel): the four photocurrents (and the
  junctions' dark current), which flow in every pixel whether its row is selected or not.

The array reads one row at a time, back to back: a row slot lasts
``T_row = 1 / (rows x frame_rate)``; the precharge holds the lines for ``T_PRE`` and releases
them for the rest of the slot. The bench runs two slots and measures the second, which
starts from what the first left (discharged lines recharged by the next precharge): the
periodic steady state of a column. Chip: ``cols x (read + bias) + rows x cols x photo``
(one bias mirror per column: the bench's).

Independent path (``estimate``): charge conservation, bias currents x supply: each loop's
tail carries ``i_bias`` all the time its row is selected, and in the steady state every
coulomb of it comes from the supply; the mirror carries ``i_bias`` always; the photocurrents
flow from the supply in every pixel. The inverters' crowbar current is not estimated (the
SPICE figure is the larger by it).
"""
from __future__ import annotations

from dataclasses import replace

from ...errors import ConfigError
from ...spice.netlist import Element, Pwl, Tran
from .circuit import EDGE, T_PRE, ratio_bench

BLOCKS = ("read", "bias", "photo")
#: the bench's illumination: each pair carries i_bias in all, equal halves (ratio 1, the
#: family experiment's unit intensity)
INTENSITY = 1.0


def row_period(design) -> float:
    a = design.array
    t_row = 1.0 / (a.rows * a.frame_rate)
    if t_row <= T_PRE + 10 * EDGE:
        raise ConfigError(design.source, "array.frame_rate", a.frame_rate,
                          f"a frame rate whose row slot 1 / (rows x frame_rate) exceeds the {T_PRE * 1e6:g} us "
                          f"precharge (at most {1.0 / (a.rows * (T_PRE + 10 * EDGE)):.4g} Hz for {a.rows} rows)")
    return t_row


def pixel_currents(design) -> tuple:
    half = 0.5 * INTENSITY * design.readout.i_bias
    return ((half, half), (half, half))


def bench(design):
    """Two row slots of one column, each block on its own supply."""
    vdd, t_row = design.tech.supply, row_period(design)
    net = ratio_bench(design, [pixel_currents(design)], design.readout.i_bias, title="vfy_power_ratio")
    els = []
    for e in net.elements:
        n = e.name.lower()
        if n == "vpre":
            e = replace(e, value=Pwl(((0.0, 0.0), (T_PRE, 0.0), (T_PRE + EDGE, vdd), (t_row, vdd),
                                      (t_row + EDGE, 0.0), (t_row + T_PRE, 0.0), (t_row + T_PRE + EDGE, vdd))))
        elif n.startswith("xp"):
            e = replace(e, nodes=tuple("vdd_photo" if x == "vdd" else x for x in e.nodes))
        elif n.startswith("xc_"):
            e = replace(e, nodes=tuple("vdd_read" if x == "vdd" else x for x in e.nodes))
        elif n == "ibias":
            e = replace(e, nodes=tuple("vdd_bias" if x == "vdd" else x for x in e.nodes))
        els.append(e)
    els += [Element(f"Vdd_{b}", (f"vdd_{b}", "0"), vdd) for b in BLOCKS]
    stop = 2 * t_row
    return replace(net, elements=tuple(els), analysis=Tran(EDGE, stop, 0.0, stop / 4000),
                   saves=tuple(f"i(vdd_{b})" for b in BLOCKS))


def from_result(design, r) -> dict:
    """Per-block mean power of the bench's second slot (W) and the chip's."""
    import numpy as np
    t_row, vdd = row_period(design), design.tech.supply
    time = r.time
    m = time >= t_row
    tt = np.concatenate([[t_row], time[m]])
    col = {}
    for b in BLOCKS:
        p = -vdd * np.asarray(r[f"i(vdd_{b})"])
        col[b] = float(np.trapezoid(np.interp(tt, time, p), tt)) / (tt[-1] - tt[0])
    a = design.array
    chip = {"read": a.cols * col["read"], "bias": a.cols * col["bias"], "photo": a.rows * a.cols * col["photo"]}
    return {"frame_period_s": 1.0 / a.frame_rate, "row_period_s": t_row, "per_column_W": col,
            "chip_blocks_W": chip, "chip_W": sum(chip.values()), "pixel_W": col["photo"],
            "column_W": col["read"] + col["bias"], "estimate": estimate(design)}


def measure(design, backend: str = "batch") -> dict:
    from ...spice import simulate_many
    return from_result(design, simulate_many([bench(design)], backend=backend, jobs=1)[0])


def estimate(design) -> dict:
    """Bias currents x supply (see the module docstring)."""
    vdd, a, ib = design.tech.supply, design.array, design.readout.i_bias
    photo = vdd * sum(i for pair in pixel_currents(design) for i in pair)
    chip = {"read": a.cols * vdd * 2 * ib, "bias": a.cols * vdd * ib, "photo": a.rows * a.cols * photo}
    return {"chip_blocks_W": chip, "chip_W": sum(chip.values()), "frame_period_s": 1.0 / a.frame_rate}
