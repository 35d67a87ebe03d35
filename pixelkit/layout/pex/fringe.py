"""The fringe capacitance of one edge of an isolated conductor over a plane (the extraction's per-edge
term, ``capacitance.py``; the corner fields and the top-face covers take their charge from it).

T. Sakurai and K. Tamaru, "Simple formulas for two- and three-dimensional capacitances", IEEE Trans.
Electron Devices 30(2), 1983: their isolated-line formula less its plate term, per edge.
"""
from __future__ import annotations


def fringe(eps: float, t: float, h: float) -> float:
    """Fringe capacitance per length (F/m) of one edge of a conductor of thickness t, h above a plane."""
    return eps * 1.40 * (t / h) ** 0.222
