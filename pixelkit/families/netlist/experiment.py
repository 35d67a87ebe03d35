"""``pixelkit simulate`` on a netlist design: the role measurements (``rolepix``) of the designer's pixel,
the same decks ``verify`` runs: conversion gain, full well, image lag, read noise, dark current, power."""
from __future__ import annotations

import time

from ...constants import Q


def run_netlist_experiment(design, backend: str = "batch", jobs: int | None = None) -> dict:
    from ...rolepix import suite
    t0 = time.perf_counter()
    raw = suite.run_experiment_groups(design, design.name, backend)
    f = suite.figures(raw)
    return {"design": design.name, "family": "netlist", "backend": backend,
            "conversion_gain_uV_per_e": f["conversion_gain"] * Q * 1e6, "full_well_e": f["full_well"] / Q,
            "saturation_V": raw["signal"]["v_sat_V"], "read_noise_e": f["read_noise"] / Q,
            "image_lag_pct": 100 * f["image_lag"], "image_lag_e": raw["lag"]["lag_e"],
            "dark_current_e_per_s": f["dark_current"] / Q, "power_chip_W": f["power_chip"],
            "ladder": {"electrons": raw["signal"]["ladder"]["electrons"],
                       "signal_V": raw["signal"]["ladder"]["signal_V"]},
            "wall_s": time.perf_counter() - t0}


def describe(design) -> dict:
    """What the kit made of the netlist (``pixelkit models``: a designer's pixel has no closed forms)."""
    c = design.cell()
    return {"subckt": c.subckt.name, "roles": dict(c.roles), "bias_V": dict(c.bias), "probes": dict(c.probes),
            "light_devices": {x.name: x.area for x in design.netlist.light},
            "subcircuits": [s.name for s in c.support], "elements": len(c.subckt.elements)}
