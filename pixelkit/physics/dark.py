"""Photodiode dark current: area and perimeter terms, doubling with temperature.

    I_d(T) = (J_A A + J_P P) 2^((T - T_ref) / T_d)     (EFFECTS.md row 3)
"""
from __future__ import annotations


def dark_current(area: float, perimeter: float, temperature_K: float, pd) -> float:
    """Dark current (A) of a PD of ``area``/``perimeter`` with the technology's ``pd`` section."""
    base = pd.dark_area * area + pd.dark_perimeter * perimeter
    return base * 2.0 ** ((temperature_K - pd.t_ref) / pd.dark_doubling)
