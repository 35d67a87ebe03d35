"""The row driver of the boosted gate rail (``pixel.gate_drive = "boosted"``): the circuit the chip
puts between a logic input at the supply's levels and a gate line (EC, TG, RST) that swings to
the rail ``vgate`` (``pixel.v_gate``, brought to the chip from a pad as a regulated supply).

A plain inverter on the rail is not enough at the low supply: with the input high at 2.97 V
(3.3 V - 10 %) and the rail at 3.6 V, its P device sees 0.63 V of gate drive and is not off. So the
driver is a level shifter: an input inverter on ``vdd`` (``inb``), a pair of N devices pulled by
``in`` / ``inb`` against a cross-coupled pair of weak P devices on ``vgate`` (nodes ``a`` / ``b``:
each swings the whole rail, so neither P device is ever half on), and an output inverter on
``vgate`` driving the line from ``a``: non-inverting, ``out`` = ``vgate`` when ``in`` is high, 0
when it is low. The P devices on the rail sit in their own n-well, tied to ``vgate``.

The sizes are fixed (W / L in m below): the N pair is 4 times as wide as the P pair it overpowers
(at ss -20 degC, -10 % supply and the design's 3.6 V rail the shifter still switches:
tests/test_rowdriver.py);
the output inverter drives a small sign-off array's lines. The simulations' benches keep the
ideal gate-level sources (docs/revisions.md says what that leaves out); this circuit is what the
layout draws for the choice and what LVS compares it against.
"""
from __future__ import annotations

from ..spice.netlist import Subckt
from .devices import mosfet

#: the subcircuit's name and ports (``0``: the substrate / vss)
NAME = "rowdrv"
PORTS = ("in", "out", "vdd", "vgate")
#: (name, kind, drain, gate, source, bulk, W, L): the devices, in m
DEVICES = (
    ("ni", "n", "inb", "in", "0", "0", 1.0e-6, 0.28e-6),
    ("pi", "p", "inb", "in", "vdd", "vdd", 2.0e-6, 0.28e-6),
    ("n1", "n", "a", "in", "0", "0", 4.0e-6, 0.28e-6),
    ("n2", "n", "b", "inb", "0", "0", 4.0e-6, 0.28e-6),
    ("p1", "p", "a", "b", "vgate", "vgate", 1.0e-6, 0.5e-6),
    ("p2", "p", "b", "a", "vgate", "vgate", 1.0e-6, 0.5e-6),
    ("no", "n", "out", "a", "0", "0", 2.0e-6, 0.28e-6),
    ("po", "p", "out", "a", "vgate", "vgate", 4.0e-6, 0.28e-6),
)


def boosted(design) -> bool:
    """Whether the chip draws row drivers on a ``vgate`` rail (the gate-drive choice)."""
    return design.pixel.gate_drive == "boosted"


def row_driver(design) -> Subckt:
    """The level-shifting row driver ``rowdrv`` (ports ``in out vdd vgate``)."""
    return Subckt(NAME, PORTS, tuple(mosfet(name, d, g, s, b, w, l_, design.tech, kind)
                                     for name, kind, d, g, s, b, w, l_ in DEVICES))


def driven_lines(rows: int) -> tuple:
    """The gate lines a boosted chip drives from the rail: the global EC / TG of both arrays, then
    each row's RST (RS, the row select, stays at the supply's levels: a pin)."""
    return ("ec_p", "tg_p", "ec_s", "tg_s", *(f"{k}_{r}" for r in range(rows) for k in ("rst_p", "rst_s")))


def driver_input(line: str) -> str:
    """The chip pin of a driven line's driver input (logic levels)."""
    return f"{line}_in"


__all__ = ["row_driver", "boosted", "driven_lines", "driver_input", "NAME", "PORTS", "DEVICES"]
