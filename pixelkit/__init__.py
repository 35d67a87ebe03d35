"""pixelkit: circuit-level CMOS image-sensor pixel and readout design kit.

``import pixelkit as pk`` gives the documented API of :mod:`pixelkit.api`
(``pk.load_design``, ``pk.bench``, ``pk.simulate``, ``pk.measure_signals``, ``pk.size``,
``pk.layout_design``, ``pk.diagnose``, ...). Names are imported on first use, so
``import pixelkit`` stays fast.
"""
from __future__ import annotations

__all__ = ["load_design", "benches", "bench", "simulate", "simulate_many", "measure_signals", "write_waveforms",
           "export_deck", "models", "experiment", "size", "layout_design", "diagnose", "sign_off", "close_design",
           "WorkingRangeWarning"]


def __getattr__(name):
    if name in __all__:
        from . import api
        return getattr(api, name)
    raise AttributeError(f"module 'pixelkit' has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + __all__)
