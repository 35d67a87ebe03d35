"""Pixel families: which one a design file describes, and its loader, experiment and models.

A design file names its family with ``family = "..."``; without it the file is a
dual-pixel design (``pixelkit.design``). The other families live in
``pixelkit.families``; each has a loader, an experiment (``pixelkit simulate``)
and a closed-form table (``pixelkit models``).
"""
from __future__ import annotations

import importlib
from pathlib import Path

from .errors import ConfigError
from .schema import read_toml

DEFAULT = "dual_pixel"
#: family -> (module of the loader, loader, module of the experiment, experiment)
FAMILIES = {
    "wdr": ("families.wdr.design", "load_wdr_design", "families.wdr.experiment", "run_wdr_experiment"),
    "ratio": ("families.ratio.design", "load_ratio_design", "families.ratio.experiment", "run_ratio_experiment"),
    "pixel4t": ("families.pixel4t.design", "load_pixel4t_design", "families.pixel4t.experiment",
                "run_pixel4t_experiment"),
    "netlist": ("families.netlist.design", "load_netlist_design", "families.netlist.experiment",
                "run_netlist_experiment"),
}
#: the families read by role with true CDS (``rolepix``): verify runs their specs like the dual pixel's
ROLE_FAMILIES = ("pixel4t", "netlist")


#: family -> regression figure -> (relative, absolute tolerance in the figure's SI unit)
REGRESS_TOLERANCES = {
    "wdr": {"decode_max_err_frac": (0.0, 0.01), "dr_db": (0.0, 0.5), "cvdr_db": (0.0, 0.2),
            "i_max_A": (0.01, 0.0), "knee.i_knee_model_A": (0.01, 0.0), "i_dark_A": (0.05, 0.0)},
    "ratio": {"ratio_law_max_err_frac": (0.0, 0.005), "interval_law_max_err_frac": (0.0, 0.005),
              "tau_s": (0.01, 0.0), "rf_min_spice": (0.01, 0.0),
              "high_bias.ratio_law_max_err_frac": (0.0, 0.01), "intensity_spread_frac": (0.0, 0.01)},
    "pixel4t": {"conversion_gain_uV_per_e": (0.01, 0.0), "full_well_e": (0.01, 0.0), "read_noise_e": (0.02, 0.0),
                "image_lag_pct": (0.0, 0.01), "dark_current_e_per_s": (0.03, 0.0), "power_chip_W": (0.01, 0.0),
                "ppd_full_well.spice_e": (0.005, 0.0), "transfer_curve.max_abs_err_e": (0.0, 3.0)},
    "netlist": {"conversion_gain_uV_per_e": (0.01, 0.0), "full_well_e": (0.01, 0.0), "read_noise_e": (0.02, 0.0),
                "image_lag_pct": (0.0, 0.01), "dark_current_e_per_s": (0.03, 0.0), "power_chip_W": (0.01, 0.0)},
}


def regress_tolerances(family: str) -> dict:
    return REGRESS_TOLERANCES[family]


def family_of(path) -> str:
    """The ``family`` key of a design file (default: the dual pixel), validated."""
    fam = read_toml(Path(path), "design").get("family", DEFAULT)
    if fam != DEFAULT and fam not in FAMILIES:
        raise ConfigError(str(path), "family", fam, f"one of {', '.join([DEFAULT, *FAMILIES])}")
    return fam


def _attr(module: str, name: str):
    return getattr(importlib.import_module(f"{__package__}.{module}"), name)


def load_family_design(path, family: str):
    mod, fn, _, _ = FAMILIES[family]
    return _attr(mod, fn)(path)


def run_family(path, family: str, backend: str = "batch", jobs: int | None = None) -> dict:
    """The family's experiment on the design at ``path`` (``pixelkit simulate``)."""
    _, _, mod, fn = FAMILIES[family]
    return _attr(mod, fn)(load_family_design(path, family), backend=backend, jobs=jobs)


def run_loaded(design, family: str, backend: str = "batch", jobs: int | None = None) -> dict:
    """The family's experiment on a design already loaded (a role family's post-layout view)."""
    _, _, mod, fn = FAMILIES[family]
    return _attr(mod, fn)(design, backend=backend, jobs=jobs)


def family_waveforms(path, family: str, out, backend: str = "batch", design=None) -> str:
    """Write the waveforms of the family's main bench (its experiment's sweep deck; a cache hit)."""
    from .api import write_waveforms
    from .families import goldens
    from .spice import simulate
    d = design or load_family_design(path, family)
    if family in ROLE_FAMILIES:   # the lag deck: flush, window, window (dark / small / bright pixels)
        from .rolepix.signal import lag_run
        _out, r, _net, _lad = lag_run(d, None, backend)
        return str(write_waveforms(r, out))
    net = goldens.wdr_sweep_of(d) if family == "wdr" else goldens.ratio_sweep_of(d)
    return str(write_waveforms(simulate(net, backend=backend), out))


def family_models(path, family: str) -> dict:
    """Closed-form figures of the family (``pixelkit models``)."""
    d = load_family_design(path, family)
    if family == "wdr":
        from .families.wdr.model import figures
        return {"design": d.name, "family": family, **figures(d)}
    if family == "pixel4t":
        from .families.pixel4t.model import figures
        return {"design": d.name, "family": family, **figures(d)}
    if family == "netlist":
        from .families.netlist.experiment import describe
        return {"design": d.name, "family": family, **describe(d)}
    from .families.ratio.circuit import tau_nominal
    from .families.ratio.law import resolution
    ro = d.readout
    return {"design": d.name, "family": family, "tau_nominal_s": tau_nominal(d, ro.i_bias),
            **resolution(ro.lsb_per_tau, ro.counter_bits)}


def family_text(result: dict) -> str:
    """Human-readable lines: every scalar figure of a family result."""
    lines = [f"{result.get('design', '?')} ({result.get('family', '?')} pixel)"]
    for k, v in result.items():
        if isinstance(v, float):
            lines.append(f"  {k:<28} {v:.6g}")
        elif k == "waveforms":
            lines.append(f"  {k:<28} {v}")
        elif isinstance(v, dict) and all(isinstance(x, (int, float)) for x in v.values()):
            lines += [f"  {k}.{a:<{max(1, 27 - len(k))}} {x:.6g}" for a, x in v.items()]
    return "\n".join(lines)
