"""The surrogate's SPICE runs: what is measured, and how the measurements are packed into decks.

A *unit* is one chain's measurement (``chains``): its array, what it is and its charge (a grid
index of ``nominal.grids``):

- ``sweep``: the nominal chain at grid charge k (``nominal.N_GRID`` charges);
- ``light``: a current on the AFE's virtual ground (``LIGHT_I``), at ``LIGHT_Q_PICK`` charges;
- ``site``: a perturbation at one site of ``responses.SITES`` at one of its amplitudes, at
  ``responses.Q_PICK`` charges;
- ``temp``: the nominal chain at another temperature (``TEMP_OFFSETS_K`` from the design's), at
  ``TEMP_Q_PICK`` charges: the nominal levels move with the die temperature (threshold voltages,
  mobility: +0.8 mV/K on the reference design's column level);
- ``val``: the nominal chain between two grid charges (``VAL_PICK``; at the design temperature and at
  ``VAL_T_OFFSET_K`` from it), run on the dual-pixel bench itself: the surrogate's error against fresh
  SPICE of the bench a user runs, on decks its tables were not built from.

Packing (``jobs``): on a schematic view every chain of a deck is a measurement of its own (``chains.packed``:
four chains of one array per deck, the same cost as the dual-pixel bench's one primary and three
secondary chains, which measured a primary unit beside three copies of a secondary one); the
``col_g`` site's units need the swept reset level (their conductance's pivot) and run in a second
round. A post-layout view keeps the dual-pixel bench (its column lines couple): one deck per primary
unit, the secondary's unit of the same kind on every secondary chain (the readout light: the
secondary's currents three to a deck).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from . import chains as ch
from . import responses

N_GRID = 22
# readout-light decks: grid charges, and per primary current the three secondary currents that shared its
# dual-pixel deck (A); both signs, over the range a 3e-11 - 3e-10 m^2 junction sees in a lab campaign
LIGHT_Q_PICK = (2, 5, 7, 9, 10, 11, 12, 13, 15, 17, 20)
LIGHT_I = ((0.5e-9, (0.7e-9, -0.7e-9, 2e-9)), (-0.5e-9, (-2e-9, 4e-9, -4e-9)),
           (5e-9, (8e-9, -8e-9, 20e-9)), (-5e-9, (-20e-9, 50e-9, -50e-9)),
           (1.5e-9, (1.2e-9, -30e-9, 30e-9)), (-1.5e-9, (2.8e-9, -40e-9, -65e-9)),
           (0.3e-9, (-10e-9, -13e-9, -16e-9)), (-0.3e-9, (0.35e-9, 1.6e-9, -25e-9)))
VAL_PICK = (3, 9, 12, 15, 18)
#: temperatures of the nominal's temperature table, from the design's (K): -20, 55, 85 degC at 27 degC
TEMP_OFFSETS_K = (-47.0, 28.0, 58.0)
TEMP_Q_PICK = (0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 21)   # as dense as the sites': the levels' T shift bends
                                                            # where the column reaches its rail
#: the held-out temperature (from the design's) and its charges (indices into VAL_PICK)
VAL_T_OFFSET_K = 18.0
VAL_T_PICK = (1, 3)


#: the packing's version (in the surrogate's key): decks of one array, temperature and charge
PACKING = 3


@dataclass(frozen=True)
class Unit:
    array: str
    kind: str                  # sweep | light | site | temp | val
    k: int                     # grid index (val: after which the charge lies halfway)
    site: str = ""
    j: int = 0                 # amplitude index (site)
    amp: float = 0.0           # the site's amplitude, or the light current (A)
    dT: float = 0.0            # temperature from the design's (K)


def currents(array: str) -> tuple:
    return tuple(p for p, _ in LIGHT_I) if array == "primary" else tuple(s for _, ss in LIGHT_I for s in ss)


def units(design, q_grid: dict, array: str) -> list:
    """Every unit of ``array`` but the validation ones, in a fixed order."""
    out = [Unit(array, "sweep", k) for k in range(N_GRID)]
    out += [Unit(array, "temp", k, dT=dT) for dT in TEMP_OFFSETS_K for k in TEMP_Q_PICK]
    out += [Unit(array, "light", k, amp=i) for k in LIGHT_Q_PICK for i in currents(array)]
    for name, s in responses.SITES.items():
        amps = s.amps(array, q_grid[array][-1])
        out += [Unit(array, "site", k, name, j, amps[j]) for j in range(len(amps)) for k in responses.Q_PICK]
    return out


def validation_units(array: str) -> list:
    return [Unit(array, "val", k) for k in VAL_PICK] + \
           [Unit(array, "val", VAL_PICK[i], dT=VAL_T_OFFSET_K) for i in VAL_T_PICK]


def charge(q_grid: dict, u: Unit) -> float:
    q = q_grid[u.array]
    return float((q[u.k] + q[u.k + 1]) / 2) if u.kind == "val" else float(q[u.k])


def _at(design, dT: float):
    return design if dT == 0 else replace(design, temperature=design.temperature + dT)


def _perturb(net, design, chain, u: Unit, pivots):
    from . import circuit_edits as ce
    if u.kind == "light":
        return ce.add_to_subckt(net, chain.afe, ce.vm_current(design, chain.array, u.amp))
    if u.kind == "site":
        return responses.SITES[u.site].edit(net, design, chain, u.amp, pivots)
    return net


@dataclass
class Job:
    """One deck: its netlist and the unit each chain measures (None: a chain measuring nothing new)."""
    net: object
    chains: tuple
    units: tuple


def _packed_jobs(design, q_grid, us, pivots, tag) -> list:
    """Four chains of one array, temperature and charge to a deck (the last deck of a charge may hold fewer):
    a site's response is the difference of two chains at one charge, and chains at one charge in decks of
    the same make keep the same time steps, so the integration error cancels in it (mixing charges in a
    deck left 0.2 - 0.4 mV between a response and the dual-pixel bench's; one charge per deck, 0.1 mV)."""
    out = []
    groups: dict = {}
    for u in us:   # a temperature's plain chains are compared with the sweep's, in other decks anyway: any charges
        groups.setdefault((u.array, u.dT, -1 if u.kind == "temp" else u.k), []).append(u)
    for (array, dT, k), g in groups.items():
        d = _at(design, dT)
        for n in range(0, len(g), ch.PACK):
            part = g[n:n + ch.PACK]
            net, cs = ch.packed(d, array, [charge(q_grid, u) for u in part],
                                f"gap{tag}{array[0]}{int(round(dT))}_{k}_{n // ch.PACK}".replace("-", "m"))
            for c, u in zip(cs, part):
                net = _perturb(net, d, c, u, pivots)
            out.append(Job(net, cs, tuple(part)))
    return out


def _standard_jobs(design, q_grid, us, pivots, tag) -> list:
    """The dual-pixel bench: each primary unit with its secondary counterpart (the same kind, charge index,
    site and amplitude index on every secondary chain; a light unit with the three secondary currents of its
    ``LIGHT_I`` entry)."""
    n = design.secondary_per_pixel
    prim = [u for u in us if u.array == "primary"]
    sec = [u for u in us if u.array == "secondary"]
    by = {}
    for u in sec:
        by.setdefault((u.kind, u.k, u.site, u.j, u.dT), []).append(u)
    light_s = {k: [u for u in sec if u.kind == "light" and u.k == k] for k in LIGHT_Q_PICK}
    out = []
    for m, up in enumerate(prim):
        if up.kind == "light":
            i = currents("primary").index(up.amp)
            mates = light_s[up.k][3 * i:3 * i + 3]
        else:
            mates = by.get((up.kind, up.k, up.site, up.j, up.dT), [])[:1] * n
        d = _at(design, up.dT)
        net, cs = ch.standard(d, charge(q_grid, up), tuple(charge(q_grid, u) for u in mates) or 0.0,
                              f"gap{tag}s{m}")
        todo = (up, *mates)
        if up.kind == "site" and up.site == "a_ol":   # one macromodel for every AFE of this bench: once
            net = _perturb(net, d, cs[0], up, pivots)
        else:
            for c, u in zip(cs, todo):
                net = _perturb(net, d, c, u, pivots)
        out.append(Job(net, cs, todo + (None,) * (len(cs) - len(todo))))
    return out


def jobs(design, q_grid: dict, us: list, pivots=None, tag: str = "") -> list:
    """The decks measuring units ``us`` (see the module docstring); validation units always on the bench."""
    val = [u for u in us if u.kind == "val"]
    rest = [u for u in us if u.kind != "val"]
    make = _packed_jobs if ch.packable(design) else _standard_jobs
    return _standard_jobs(design, q_grid, val, pivots, tag + "v") + make(design, q_grid, rest, pivots, tag)


def measure(design, job_list: list, results: list) -> dict:
    """{unit: (signal level, reset level, AFE output)} (a unit measured on several chains: their mean)."""
    from ..circuits.testbench import timings
    from ..measure.pixel import levels
    tm = timings(design, design.experiment.t_window)
    got: dict = {}
    for job, r in zip(job_list, results):
        for c, u in zip(job.chains, job.units):
            if u is None:
                continue
            t = tm[c.array]
            sig, rst = levels(r, c.col, t)
            got.setdefault(u, []).append((sig, rst, float(r.at(c.out, t.t_reset_level(0)))))
    return {u: tuple(np.mean(v, axis=0)) for u, v in got.items()}


def pivots_of(got: dict) -> dict:
    """The ``col_g`` site's pivots: each array's mean reset level on the validation decks at the design
    temperature (the first round)."""
    return {a: float(np.mean([v[1] for u, v in got.items() if u.kind == "val" and u.array == a and u.dT == 0]))
            for a in ("primary", "secondary")}


def plan(design, q_grid: dict, pivots=None) -> list:
    """[first round's jobs, second round's]: the validation decks (the dual-pixel bench), whose reset levels
    are the ``col_g`` site's pivots; then every other unit (``pivots=None``: the first round only)."""
    first = jobs(design, q_grid, [u for a in ("primary", "secondary") for u in validation_units(a)])
    if pivots is None:
        return [first]
    return [first, jobs(design, q_grid, [u for a in ("primary", "secondary") for u in units(design, q_grid, a)],
                        pivots)]


def run(design, q_grid: dict, backend: str = "batch") -> tuple[dict, dict, list]:
    """(every unit's measurement, the pivots, the titles of decks the engine could only finish with looser
    tolerances)."""
    from .exact import simulate_exact
    first, = plan(design, q_grid)
    res = simulate_exact([j.net for j in first], backend=backend)
    got = measure(design, first, res)
    pivots = pivots_of(got)
    second = plan(design, q_grid, pivots)[1]
    res2 = simulate_exact([j.net for j in second], backend=backend)
    got.update(measure(design, second, res2))
    loose = [r.meta["title"] for r in list(res) + list(res2) if r.meta.get("retried")]
    return got, pivots, loose
