"""``pixelkit verify`` on a ratio design: its ``[spec]`` on the figures this family measures
(``design.FIGURES``: the chip's power at the design's frame rate, ``power.py``) at every
condition of the grid, in the dual pixel's sign-off table. No Monte Carlo yet: the family's
devices have no mismatch draw, and a Monte Carlo without spread is never a pass."""
from __future__ import annotations

import time
from dataclasses import replace

from ...errors import ConfigError, SimulationError
from ...verify import conditions
from . import power


def at(design, cond):
    """``design`` at ``cond``: the model corner, the die temperature and the supply (the loop's
    source, select and clamp levels are references a chip regulates, and stay as designed)."""
    supply = design.tech.supply * (1.0 + cond.supply)
    for what, v in (("loop.v_source", design.loop.v_source), ("readout.v_select", design.readout.v_select),
                    ("readout.v_clamp_gate", design.readout.v_clamp_gate)):
        if v >= supply:
            raise ConfigError(design.source, what, v, f"a level below the supply at condition {cond.label} "
                              f"({supply:g} V)")
    tech = replace(design.tech, supply=supply) if cond.supply else design.tech
    return replace(design, corner=cond.corner, temperature=cond.temperature, tech=tech)


def _task(task):
    design, cond, backend = task
    try:
        return {"ok": True, "raw": power.measure(at(design, cond), backend)}
    except SimulationError as exc:
        return {"ok": False, "error": f"{exc.what or exc.deck}: {exc.message}"}


def verify(design, corners=None, temperatures=None, supplies=None, mc=None, seed=None, backend: str = "batch",
           jobs=None, scheduler=None) -> dict:
    from ...spice.executors import run_tasks
    from ...verify.run import _clean, _power
    from ...verify.signoff import table
    if not design.spec:
        raise ConfigError(design.source, "spec", None, "a [spec] table with at least one spec (docs/verify.md)")
    if mc or design.verify.mc:
        raise ConfigError(design.source, "--mc" if mc else "verify.mc", mc or design.verify.mc,
                          "0 for the ratio family (its devices have no mismatch draw yet)")
    t0 = time.perf_counter()
    grid = conditions.grid(design, corners, temperatures, supplies)
    for c in grid:
        power.row_period(at(design, c))   # refused before any run
    tasks = [(design, c, backend) for c in grid]
    outs = [None] * len(tasks)
    for i, out in run_tasks(_task, tasks, jobs=jobs, scheduler=scheduler, desc="verify"):
        outs[i] = out
    raw, errors = {}, []
    for c, out in zip(grid, outs):
        if out["ok"]:
            raw[c] = {"power": out["raw"]}
        else:
            errors.append({"condition": c.label, "group": "power", "sample": None, "error": out["error"]})
    values = {c: {"power_chip": r["power"]["chip_W"]} for c, r in raw.items()}
    rows = table(design, grid, values, [], [])
    return {"design": design.name, "revision": design.revision, "family": "ratio", "rows": rows,
            "grid": {"corners": sorted({c.corner for c in grid}),
                     "temperatures_C": sorted({round(c.temperature - 273.15, 6) for c in grid}),
                     "supplies": sorted({c.supply for c in grid}), "conditions": len(grid)},
            "mc": {"samples": 0, "seed": design.verify.seed, "source": None, "draws": None,
                   "condition": conditions.nominal(design).label, "confidence": design.verify.confidence},
            "supply_V": design.tech.supply, "view": "schematic",
            "conditions": [{**c.as_dict(), "label": c.label, "figures": values.get(c, {})} for c in grid],
            "mc_values": {}, "raw": _clean({c.label: raw.get(c, {}) for c in grid}),
            "power": _power(grid, raw, conditions.nominal(design)),
            "errors": errors, "tasks": len(tasks), "wall_s": time.perf_counter() - t0,
            "failed": [r["spec"] for r in rows if r["status"] == "fail"],
            "unmeasured": [r["spec"] for r in rows if r["status"] not in ("pass", "fail")]}
