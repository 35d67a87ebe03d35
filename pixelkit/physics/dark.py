"""Photodiode dark current: area and perimeter terms, doubling with temperature.

    I_d(T) = (J_A A + J_P P) 2^((T - T_ref) / T_d)     (J_A, J_P: area and perimeter densities)

This is the kit's one dark-current law: the SPICE diode card writes its
saturation currents from ``dark_scale`` at the deck temperature (see
``circuits.devices.photodiode_model``), and the FD leakage of the storage node
(``fd.leakage``) follows the same law on the FD diffusion.
"""
from __future__ import annotations


def dark_scale(temperature_K: float, pd) -> float:
    """Factor 2^((T - T_ref)/T_d) of the technology's ``pd`` section."""
    return 2.0 ** ((temperature_K - pd.t_ref) / pd.dark_doubling)


def dark_current(area: float, perimeter: float, temperature_K: float, pd) -> float:
    """Dark current (A) of a PD of ``area``/``perimeter`` with the technology's ``pd`` section."""
    return (pd.dark_area * area + pd.dark_perimeter * perimeter) * dark_scale(temperature_K, pd)
