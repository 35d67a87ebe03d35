"""Netlist data type and writer, ngspice backends, raw files, results, cache, parallel runs."""
from .engine import simulate, simulate_many
from .netlist import Element, Model, Netlist, Param, Pulse, Pwl, Subckt, Tran
from .result import Result

__all__ = ["simulate", "simulate_many", "Element", "Model", "Netlist", "Param", "Pulse", "Pwl",
           "Subckt", "Tran", "Result"]
