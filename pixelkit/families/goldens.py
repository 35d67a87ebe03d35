"""Golden netlists of the other families, at their reference designs (``designs/*.toml``).

Registered in ``pixelkit/registry.py`` beside the dual pixel's; each generator
takes (and ignores) the dual-pixel reference design the registry passes.
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from ..spice.netlist import Netlist, Op

DESIGNS = Path(__file__).resolve().parents[2] / "designs"


@lru_cache(maxsize=None)
def _wdr():
    from .wdr.design import load_wdr_design
    return load_wdr_design(DESIGNS / "wdr_pixel.toml")


@lru_cache(maxsize=None)
def _ratio():
    from .ratio.design import load_ratio_design
    return load_ratio_design(DESIGNS / "ratio_pixel.toml")


def _cells(design, title, subckts) -> Netlist:
    return Netlist(title=title, elements=(), analysis=Op(), subckts=tuple(subckts),
                   includes=design.tech.models.includes(design.corner or None))


def wdr_cells(_ref) -> Netlist:
    from .wdr.circuit import wdr_pixel
    return _cells(_wdr(), "wdr_pixel", [wdr_pixel(_wdr())])


def wdr_sweep_of(design) -> Netlist:
    """The WDR experiment's main deck for ``design``."""
    from .wdr.circuit import wdr_bench
    from .wdr.experiment import currents
    return wdr_bench(design, currents(design))


def wdr_sweep(_ref) -> Netlist:
    return wdr_sweep_of(_wdr())


def ratio_cells(_ref) -> Netlist:
    from .ratio.circuit import column_readout, ratio_loop, ratio_pixel
    d = _ratio()
    return _cells(d, "ratio_pixel", [ratio_loop(d), ratio_pixel(), column_readout(d)])


def ratio_sweep_of(design) -> Netlist:
    """The ratio experiment's deck at the nominal bias for ``design``."""
    from .ratio.circuit import ratio_bench
    from .ratio.experiment import bench_pairs, cells
    return ratio_bench(design, bench_pairs(cells(design)), design.readout.i_bias, title="ratio_bench_0")


def ratio_sweep(_ref) -> Netlist:
    return ratio_sweep_of(_ratio())


GENERATORS = {"wdr_pixel": wdr_cells, "wdr_sweep": wdr_sweep,
              "ratio_pixel": ratio_cells, "ratio_sweep": ratio_sweep}
