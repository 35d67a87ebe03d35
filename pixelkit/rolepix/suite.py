"""What ``pixelkit verify`` (and ``close``) run for a pixel read by role: the measurement groups,
the figures they give (``verify.figures.ROLE_FIGURES``) and the design at a condition. A role
design hands this module over as its ``suite`` (``families.roledesign.RoleDesign.suite``); the
dual pixel's suite is ``verify.measure`` itself."""
from __future__ import annotations

from dataclasses import replace

from ..constants import Q
from ..errors import ConfigError
from ..verify.figures import ROLE_FIGURES, groups_of
from .dark import dark
from .noise import noise
from .power import power
from .prnu import prnu
from .signal import lag, signal

FIGURES = ROLE_FIGURES
GROUPS = {"signal": signal, "lag": lag, "noise": noise, "dark": dark, "prnu": prnu, "power": power}


def run_group(group: str, design, draw=None, backend: str = "batch") -> dict:
    return GROUPS[group](design, draw, backend)


#: the groups a role pixel's ``simulate`` experiment reports (PRNU is verify's: a Monte Carlo)
EXPERIMENT_GROUPS = ("signal", "lag", "noise", "dark", "power")


def run_experiment_groups(design, label: str, backend: str = "batch") -> dict:
    """The raw measurements of ``EXPERIMENT_GROUPS``, each under a progress step named ``label: group``."""
    from ..progress import step
    raw = {}
    for g in EXPERIMENT_GROUPS:
        with step(f"{label}: {g}"):
            raw[g] = run_group(g, design, None, backend)
    return raw


def groups_for(figure_names) -> list[str]:
    return groups_of(figure_names, FIGURES)


def figures(raw: dict) -> dict:
    """Every figure the raw measurements of the groups in ``raw`` give (SI)."""
    out = {}
    sig = raw.get("signal")
    if sig:
        cg = sig["cg_V_per_e"]
        out["conversion_gain"] = cg / Q
        out["full_well"] = sig["v_sat_V"] / cg * Q
        if raw.get("noise"):
            out["read_noise"] = raw["noise"]["sigma_V"] / cg * Q
        if raw.get("dark"):
            out["dark_current"] = raw["dark"]["dark_V"] / cg * Q / raw["dark"]["dt_s"]
    if raw.get("lag"):
        out["image_lag"] = abs(raw["lag"]["lag_frac"])
    if raw.get("prnu"):
        out["prnu"] = raw["prnu"]["prnu"]
    if raw.get("power"):
        out["power_chip"] = raw["power"]["chip_W"]
    return out


def at(design, cond):
    """``design`` at ``cond``: the model corner, the die temperature and the supply (the gates driven
    from the supply follow it; a boosted rail and a regulated reset drain stay)."""
    supply = design.tech.supply * (1.0 + cond.supply)
    lv = design.levels
    if lv.v_rst is not None and lv.v_rst > supply:
        raise ConfigError(design.source, "levels.v_rst", lv.v_rst, f"a level no higher than the supply at "
                          f"condition {cond.label} ({supply:g} V)")
    tech = replace(design.tech, supply=supply) if cond.supply else design.tech
    return replace(design, corner=cond.corner, temperature=cond.temperature, tech=tech)
