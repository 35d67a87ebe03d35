"""Out-of-distribution virtual silicon: lab data made by mechanisms the surrogate never tabulates.

``silicon`` inserts each effect with the element the surrogate's response tables are measured
with (``responses``): a diagnosis that names it right there is tested in distribution. This
generator makes each effect of the library by the *physical* mechanism a chip would have, with
constants drawn from physical ranges, so the library's shape is not the data's:

- ``sf_wl``: the source follower drawn at another W and L (the model's L bins change its threshold,
  body effect and output conductance with it) -> ``sf_strength``;
- ``load_gds``: the column load drawn shorter at the same W / L (its output conductance) ->
  ``sf_gain``;
- ``afe_layout``: the AFE's capacitors as the layout leaves them: C13 larger by its wiring's fringe,
  a bottom-plate parasitic on vm, C12 off, every column its own Pelgrom draw -> ``afe_gain``;
- ``dark_junction``: PD dark current of the junction's area and perimeter, each density with its own
  generation / diffusion mix (n_i and n_i^2 with silicon's band gap, Varshni), voltage dependent
  (a transconductance on the PD node: the depletion width falls as the PD discharges) ->
  ``dark_current``;
- ``fd_junction``: the floating diffusion's junction leakage, generation / diffusion mix and voltage
  dependent (a resistor to a negative offset switched onto FD for the hold) -> ``fd_leakage``;
- ``fd_light``: light on the storage node, each array's FD under its own shield -> ``gse``;
- ``switch_injection``: the reset switch (RST) and the AFE's vm reset switches drawn wider (channel
  charge and overlap) -> ``charge_injection``;
- ``xt_diffusion``: carriers of the neighbouring primary diffusing into the secondary's junction
  (a fraction of the primary's photocurrent) -> ``crosstalk``;
- ``lag_traps``: charge of the previous frame trapped and released in this one, the traps
  saturating -> ``lag``;
- ``column_fpn``: the column loads' gate offsets along the row of columns (the bias line's and the
  ground bus's drop: a linear and a parabolic law) plus each load's Pelgrom draw -> ``column_pixel``;
- ``afe_columns``: each column's C11 along an oxide gradient plus Pelgrom, and its vm reset
  switch's width (its injection) -> ``column_afe``;
- ``layout_light``: light on the readout's junctions with the open-junction pattern of the kit's
  drawn dual pixel and AFE (``layout.pex.light``'s map of the GF180 layout: the column line, the
  sampling node and the AFE's vm / x / c, P+ and N+ with their areas), from the row's start ->
  ``readout_light``;

and effects outside the library, whose right answer is "not explained": ``col_bridge`` (two
secondary columns bridged), ``col_clamp`` (a diode clamping the column line), ``fd_pullup`` (FD
leaking to the supply, no temperature law) and ``setup_inl`` (the bench's ADC bowing the AFE
probe: the set-up is not a gain and an offset).

Every operating point is one dual-pixel bench deck (``chains.standard``) **at the operating
point's die temperature** (the device models at that temperature: the surrogate's temperature table
is tested too), under **one irradiance for both arrays** (a lab's uniform light: each array's
photocurrent is its photoactive area times it; the exposure set for one array, the other's
integration time following; a test chart for the bridged columns), with each array's own integration
time. The test set-up of a calibrated bench: per probe a gain N(1, 0.3 %) and an offset N(0, 2 mV),
which the bench states (``stated_setup``: without it a chain gain of a few per cent is the set-up's
own gain and cannot be seen, docs/gap-diagnosis.md), and 0.6 mV of temporal noise per frame over 4
frames (stated in the file). Nothing of the surrogate, the effect
library or the fitter enters: the data are ngspice's levels of these decks.

Sets with their own seeds (``SETS``): ``dev`` (what the diagnosis may be looked at on), ``heldout`` (scored
blind once, then seen: its misses were studied on new development cases) and ``heldout2`` (drawn after that, seeds
from 90000, scored blind once), in ``tests/data/gap_ood/<set>/``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..spice.netlist import Element, Model, Pwl
from . import circuit_edits as ce
from .chains import standard

#: the design the sets are of (the reference)
DESIGN = str(Path(__file__).resolve().parents[2] / "designs" / "dual_pixel_revA.toml")
NOISE_V = 0.6e-3
N_AVG = 4
#: the bench: each probe's gain and offset drawn around 1 and 0 with these standard deviations, which the bench
#: states as its calibration (a known voltage read through each probe's path; ``stated_setup``)
SETUP_GAIN_SD = 0.003
SETUP_OFFSET_SD_V = 0.002
OOD_DIR = Path(__file__).resolve().parents[2] / "tests" / "data" / "gap_ood"
SETS = {"dev": 50000, "heldout": 70000, "heldout2": 90000}
K_B = 8.617333e-5   # eV/K
#: the vm switches' width factor stays within the model's bins (GF180 nfet_03v3: W >= 0.22 um; the switches are
#: 1 um wide): a draw below it stopped ngspice ("could not find a valid modelname", held-out case 70044)
SW_W_FLOOR = 0.22
FD_LIMIT = 0.25     # storage-node charge kept below this fraction of the array's swing (as a lab shortens a wait)
PD_LIMIT = 0.6      # PD charge kept below this fraction of the full well (a lab halves a hot exposure)

# campaign -> operating points, primary t_int range (s), temperatures (degC), dark-frame probability, light
# as a fraction of the exposed array's full-well charge, extra waits (s), columns per array seen
CAMPAIGNS = {
    "lab": {"points": 10, "t_int": (50e-6, 2e-3), "temps": (25.0, 45.0, 65.0), "dark": 0.2,
            "light": (0.03, 0.6), "waits": (0.0, 10e-3, 40e-3), "columns": None},
    "hot": {"points": 10, "t_int": (2e-3, 50e-3), "temps": (45.0, 65.0, 85.0), "dark": 0.5,
            "light": (0.02, 0.3), "waits": (0.0, 10e-3), "columns": None},
    "columns": {"points": 12, "t_int": (50e-6, 2e-3), "temps": (25.0, 45.0, 65.0), "dark": 0.2,
                "light": (0.03, 0.6), "waits": (0.0, 10e-3), "columns": (6, 9)},
    # the secondary exposed for short times (so the irradiance is high: a lab looking for light on the readout)
    "bright": {"points": 10, "t_int": (20e-6, 500e-6), "temps": (25.0, 45.0, 65.0), "dark": 0.2,
               "light": (0.1, 0.6), "waits": (0.0, 10e-3), "columns": None, "lead": "secondary"},
    # a test chart: every subpixel its own irradiance within a factor of 3 of the frame's (columns next to each
    # other read different levels)
    "chart": {"points": 10, "t_int": (50e-6, 2e-3), "temps": (25.0, 45.0, 65.0), "dark": 0.1,
              "light": (0.03, 0.5), "waits": (0.0, 10e-3), "columns": None, "chart": 3.0},
}


@dataclass(frozen=True)
class Kind:
    expected: str           # the library effect it is (``out_of_library``, ``none``)
    campaign: str
    draw: object            # (rng, design) -> parameters (JSON-able)


def _u(g, lo, hi):
    return float(g.uniform(lo, hi))


def _logu(g, lo, hi):
    return float(np.exp(g.uniform(np.log(lo), np.log(hi))))


def _sign(g):
    return float(g.choice([-1.0, 1.0]))


def _junction_law(g) -> dict:
    """A reverse-biased junction's leakage: generation (~ n_i) and diffusion (~ n_i^2) mixed, the diffusion
    share at 25 degC drawn; each with a trap-level offset of its activation energy."""
    return {"diff_share": _u(g, 0.0, 0.6), "dEa_gen_eV": _u(g, -0.05, 0.1)}


def _pelgrom_scale(g):
    return _u(g, 0.3, 1.0)


KINDS = {
    "sf_wl": Kind("sf_strength", "lab", lambda g, d: {"w_factor": _logu(g, 0.6, 1.6), "l_factor": _u(g, 0.8, 1.6)}),
    "load_gds": Kind("sf_gain", "lab", lambda g, d: {"l_factor": _u(g, 0.175, 0.4)}),
    "afe_layout": Kind("afe_gain", "lab", lambda g, d: {"c13_fringe_rel": _u(g, 0.01, 0.05), "c12_rel": _u(g, -0.05, 0.05),
                                                         "cp_vm_rel": _u(g, 0.02, 0.1),
                                                         "pelgrom_scale": _pelgrom_scale(g)}),
    "dark_junction": Kind("dark_current", "hot", lambda g, d: {
        "j_area_A_cm2": _logu(g, 5e-11, 1e-9), "j_perim_A_cm": _logu(g, 5e-15, 1e-13),
        "area_law": _junction_law(g), "perim_law": _junction_law(g), "v0_V": _u(g, 0.5, 4.0)}),
    "fd_junction": Kind("fd_leakage", "lab", lambda g, d: {"i_fd_A": _logu(g, 5e-17, 5e-16), "law": _junction_law(g),
                                                           "v0_V": _u(g, 0.5, 4.0)}),
    "fd_light": Kind("gse", "lab", lambda g, d: {"pls_primary": 1.0 / _logu(g, 300, 10000),
                                                 "pls_secondary": 1.0 / _logu(g, 300, 10000),
                                                 "v0_V": _u(g, 2.0, 8.0)}),
    "switch_injection": Kind("charge_injection", "lab", lambda g, d: {"rst_w_factor": _u(g, 1.5, 3.0),
                                                                      "vm_switch_w_factor": _u(g, 1.5, 3.0)}),
    "xt_diffusion": Kind("crosstalk", "lab", lambda g, d: {"k_from_primary": _logu(g, 3e-4, 3e-3)}),
    "lag_traps": Kind("lag", "lab", lambda g, d: {"lag": _u(g, 0.01, 0.05), "q_sat_rel": _logu(g, 0.5, 3.0)}),
    "column_fpn": Kind("column_pixel", "columns", lambda g, d: {"linear_V": _sign(g) * _u(g, 0.5e-3, 3e-3),
                                                                "parabola_V": _u(g, 0.5e-3, 3e-3),
                                                                "pelgrom_scale": _pelgrom_scale(g)}),
    "afe_columns": Kind("column_afe", "columns", lambda g, d: {"c11_gradient_rel": _sign(g) * _u(g, 0.003, 0.01),
                                                               "c11_sd_rel": _u(g, 0.002, 0.006),
                                                               "switch_w_sd_rel": _u(g, 0.1, 0.4)}),
    "layout_light": Kind("readout_light", "bright", lambda g, d: {"open_scale": _logu(g, 10.0, 60.0)}),
    "col_bridge": Kind("out_of_library", "chart", lambda g, d: {"r_bridge_ohm": _u(g, 1e5, 4e5)}),
    "col_clamp": Kind("out_of_library", "lab", lambda g, d: {"clamp_at_frac": _u(g, 0.35, 0.6)}),
    "fd_pullup": Kind("out_of_library", "lab", lambda g, d: {"r_pullup_ohm": _u(g, 2e14, 1e15)}),
    "setup_inl": Kind("out_of_library", "lab", lambda g, d: {"bow_V": _sign(g) * _u(g, 2e-3, 8e-3)}),
    "none": Kind("none", "lab", lambda g, d: {}),
}
IN_LIBRARY = tuple(k for k, v in KINDS.items() if v.expected not in ("none", "out_of_library"))
OUT_OF_LIBRARY = tuple(k for k, v in KINDS.items() if v.expected == "out_of_library")


# ---- junction physics (the generator's own: the library's laws are not used) ----

def eg_si(T):
    """Silicon's band gap (eV) at T (K), Varshni's law (Eg(0) 1.170 eV, 4.73e-4 eV/K, 636 K)."""
    return 1.170 - 4.73e-4 * T * T / (T + 636.0)


def ni_rel(T, T0=298.15):
    """n_i(T) / n_i(T0): T^1.5 exp(-Eg(T) / 2kT)."""
    return (T / T0) ** 1.5 * math.exp(-eg_si(T) / (2 * K_B * T) + eg_si(T0) / (2 * K_B * T0))


def junction_law(law: dict, temp_C: float) -> float:
    """Leakage at ``temp_C`` over its value at 25 degC: generation (n_i, with a trap offset of its activation
    energy) and diffusion (n_i^2) in the drawn mix."""
    T, T0 = temp_C + 273.15, 298.15
    gen = ni_rel(T) * math.exp(-law["dEa_gen_eV"] / K_B * (1 / T - 1 / T0))
    return (1 - law["diff_share"]) * gen + law["diff_share"] * ni_rel(T) ** 2


# ---- operating points ----

def _q_max(nom, arr):
    return float(nom.q_grid[arr][-1])


def operating_points(design, nom, g, campaign: str) -> list:
    """Lab operating points: one irradiance for both arrays (as a photocurrent density ``J``, A/m^2 of
    photoactive area), the exposure set for one array (its fill drawn), the other's integration time so
    that it fills as drawn within 10 us .. 50 ms; dark frames at the design's ratio of integration times."""
    c = CAMPAIGNS[campaign]
    a_pa = {"primary": design.primary.photoactive_area, "secondary": design.secondary.photoactive_area}
    ratio = design.secondary.t_int / design.primary.t_int
    ncol = {"primary": design.primary.cols, "secondary": design.secondary.cols}
    seen = None
    if c["columns"]:
        seen = {a: sorted(g.choice(ncol[a], n, replace=False).tolist()) for a, n in zip(ncol, c["columns"])}
    ops = []
    for k in range(c["points"]):
        temp = float(g.choice(c["temps"]))
        row = int(g.integers(0, design.primary.rows))
        extra = float(g.choice(c["waits"]))
        t_p = _logu(g, *c["t_int"])
        dark = g.random() < c["dark"]
        if dark:
            J, t = 0.0, {"primary": t_p, "secondary": t_p * ratio}
        else:
            lead = c.get("lead") or ("primary" if g.random() < 0.5 else "secondary")
            other = "secondary" if lead == "primary" else "primary"
            t = {lead: t_p * (ratio if lead == "secondary" and "lead" not in c else 1.0)}
            J = _u(g, *c["light"]) * _q_max(nom, lead) / (t[lead] * a_pa[lead])
            t[other] = float(np.clip(_u(g, *c["light"]) * _q_max(nom, other) / (J * a_pa[other]), 10e-6, 50e-3))
        J_prev = J * _u(g, 0.0, 2.0)
        if seen:
            cols = {"primary": [seen["primary"][k % len(seen["primary"])]],
                    "secondary": [seen["secondary"][(3 * k + m) % len(seen["secondary"])] for m in range(3)]}
        else:
            cols = {"primary": [int(g.integers(0, ncol["primary"]))],
                    "secondary": sorted(g.choice(ncol["secondary"], 3, replace=False).tolist())}
        chart = [float(np.exp(g.uniform(-1, 1) * np.log(c["chart"]) / 2)) if c.get("chart") else 1.0
                 for _ in range(4)]
        ops.append({"temp": temp, "row": row, "extra_wait": extra, "t_int": t, "J": J, "J_prev": J_prev,
                    "cols": cols, "chart": chart})
    return ops


def _J(op, chain=None):
    """The irradiance (photocurrent density, A/m^2) on chain ``chain`` (0 primary, 1 - 3 secondaries; None:
    the frame's), a test chart's factor on it."""
    return op["J"] * (1.0 if chain is None else op["chart"][chain])


def _i(design, op, arr, prev=False, chain=None):
    f = 1.0 if chain is None else op["chart"][chain]
    return (op["J_prev"] if prev else op["J"]) * f * getattr(design, arr).photoactive_area


def _t_wait(design, op, arr):
    return (op["row"] + 1) / getattr(design, arr).f_read + op["extra_wait"]


def _fd_charge(design, op, arr, kind, p, chain=None):
    """The storage-node charge (C) an FD effect leaves over the wait (at its reference voltage; ``chain``
    None: at the frame's brightest chain)."""
    tw = _t_wait(design, op, arr)
    if kind == "fd_light":
        j = _J(op, chain) if chain is not None else op["J"] * max(op["chart"])
        return p[f"pls_{arr}"] * j * design.primary.photoactive_area * tw
    if kind == "fd_junction":
        return p["i_fd_A"] * junction_law(p["law"], op["temp"]) * tw
    return 0.0


def limit_waits(design, nom, ops, kind, p) -> None:
    """Shorten an extra wait until the storage node's charge stays within ``FD_LIMIT`` of the swing."""
    if kind not in ("fd_light", "fd_junction"):
        return
    from .silicon import wait_steps
    for op in ops:
        for extra in wait_steps(op):
            op["extra_wait"] = extra
            if all(_fd_charge(design, op, a, kind, p) * max(nom.fd_ratio[a][1]) < FD_LIMIT * _q_max(nom, a)
                   for a in ("primary", "secondary")):
                break


def _dark_extra(design, op, arr, p):
    """The dark_junction kind's current at the reset voltage (A) of one array at the op's temperature."""
    sub = getattr(design, arr)
    area_cm2, perim_cm = sub.area * 1e4, sub.perimeter * 1e2
    return (p["j_area_A_cm2"] * area_cm2 * junction_law(p["area_law"], op["temp"])
            + p["j_perim_A_cm"] * perim_cm * junction_law(p["perim_law"], op["temp"]))


def limit_exposures(design, nom, ops, kind, p) -> None:
    """Halve a hot exposure until the PD charge (light, the design's dark current and the kind's) stays within
    ``PD_LIMIT`` of the full well."""
    from ..physics.dark import dark_current
    for op in ops:
        for arr in ("primary", "secondary"):
            for _ in range(16):
                i = _i(design, op, arr) * max(op["chart"]) + dark_current(*nom.dark[arr], op["temp"] + 273.15, nom.pd)
                if kind == "dark_junction":
                    i += _dark_extra(design, op, arr, p)
                if i * op["t_int"][arr] < PD_LIMIT * _q_max(nom, arr):
                    break
                op["t_int"][arr] /= 2


# ---- circuit edits (the generator's own mechanisms) ----

SW_MODEL = Model("swood", "sw", (("vt", 1.0), ("vh", 0.0), ("ron", 1e3), ("roff", 1e22)))


def _switched_resistor(design, arr, r_ohm, v0, tag):
    """Elements inside a subpixel: a resistor ``r_ohm`` from FD to a node at -``v0`` switched in for the FD's
    hold (the deck's compressed wait): a current (V_FD + v0) / r, voltage dependent as a junction's."""
    t0, t1 = ce.hold_window(design, arr)
    e = ce.EDGE
    gate = Pwl(((0.0, 0.0), (t0, 0.0), (t0 + e, 2.0), (t1 - e, 2.0), (t1, 0.0)))
    return (Element(f"Vsw{tag}", (f"g{tag}", "0"), gate), Element(f"Vng{tag}", (f"n{tag}", "0"), -v0),
            Element(f"S{tag}", ("fd", f"m{tag}", f"g{tag}", "0"), "swood"),
            Element(f"R{tag}", (f"m{tag}", f"n{tag}"), r_ohm))


def _pd_transconductance(i_ref, v_ref, v0, tag):
    """A current from the PD of (V_PD + v0) / (v_ref + v0) x ``i_ref`` (a G element on a node at -v0)."""
    return (Element(f"Vng{tag}", (f"n{tag}", "0"), -v0),
            Element(f"G{tag}", ("pd", "0", "pd", f"n{tag}"), i_ref / (v_ref + v0)))


def _column_law(x, n, p):
    """The load gate offset of column ``x`` of ``n`` (V): linear (bias line) plus parabolic (ground bus)."""
    u = x / max(n - 1, 1) - 0.5
    return p["linear_V"] * 2 * u + p["parabola_V"] * (4 * u * u - 1 / 3)


def column_draws(design, g, kind, p, ops) -> dict:
    """Per (array, column) draws of the column kinds (the Pelgrom terms; the laws are in ``p``)."""
    from ..physics.pelgrom import cap_sigma_rel, sigma_vth
    dev, a = design.pixel.devices, design.afe
    out = {}
    cols = sorted({(arr, c) for op in ops for arr, cs in op["cols"].items() for c in cs})
    for arr, c in cols:
        n = getattr(design, arr).cols
        if kind == "column_fpn":
            dv = _column_law(c, n, p) + g.normal(0, p["pelgrom_scale"] * sigma_vth(design, dev.load_w, dev.load_l))
            out[(arr, c)] = {"dvt_V": float(dv)}
        elif kind == "afe_columns":
            u = c / max(n - 1, 1) - 0.5
            out[(arr, c)] = {"c11": float(1 + p["c11_gradient_rel"] * 2 * u + g.normal(0, p["c11_sd_rel"])),
                             "sw": float(max(SW_W_FLOOR, 1 + g.normal(0, p["switch_w_sd_rel"])))}
        elif kind == "afe_layout":
            out[(arr, c)] = {n_: float(1 + g.normal(0, p["pelgrom_scale"] * cap_sigma_rel(design, cv)))
                             for n_, cv in (("C11", a.c11), ("C12", a.c12), ("C13", a.c13))}
    return out


def deck(design, nom, op, kind, p, colp, pattern, title):
    """One operating point's dual-pixel deck at its die temperature with ``kind``'s mechanism inserted."""
    from ..physics.dark import dark_current
    d = replace(design, temperature=op["temp"] + 273.15)
    d = _variant(d, kind, p)
    t_w = design.experiment.t_window
    arrs = ("primary", "secondary", "secondary", "secondary")
    q = [(_i(design, op, a, chain=m) + dark_current(*nom.dark[a], op["temp"] + 273.15, nom.pd)) * op["t_int"][a]
         for m, a in enumerate(arrs)]
    net, cs = standard(d, q[0], tuple(q[1:]), title)
    models = []
    labels = [("primary", op["cols"]["primary"][0])] + [("secondary", x) for x in op["cols"]["secondary"]]
    for m, (c, label) in enumerate(zip(cs, labels)):
        arr = c.array
        tw = _t_wait(design, op, arr)
        t0, t1 = ce.hold_window(design, arr)
        el = []
        if kind == "dark_junction":
            i_ref = _dark_extra(design, op, arr, p) * op["t_int"][arr] / t_w
            el += _pd_transconductance(i_ref, design.pixel.v_pd_reset, p["v0_V"], "dk")
        elif kind in ("fd_junction", "fd_light") and _fd_charge(design, op, arr, kind, p, m) > 0:
            # the charge over the wait at the FD's reset voltage, voltage dependent through the conductance
            r = (design.pixel.v_fd_reset + p["v0_V"]) * (t1 - t0 - ce.EDGE) / _fd_charge(design, op, arr, kind, p, m)
            el += _switched_resistor(design, arr, r, p["v0_V"], "fdl")
            models = [SW_MODEL]
        elif kind == "xt_diffusion" and arr == "secondary":
            el.append(Element("Ixt", ("pd", "0"), p["k_from_primary"] * _i(design, op, "primary", chain=0)
                              * op["t_int"][arr] / t_w))
        elif kind == "lag_traps":
            q_prev = _i(design, op, arr, prev=True, chain=m) * op["t_int"][arr]
            q_sat = p["q_sat_rel"] * _q_max(nom, arr)
            el.append(Element("Ilag", ("pd", "0"), p["lag"] * q_sat * (1 - math.exp(-q_prev / q_sat)) / t_w))
        elif kind == "fd_pullup":
            el.append(Element("Rpu", ("fd", "vdd"), p["r_pullup_ohm"] * (t1 - t0) / tw))
        elif kind == "switch_injection":     # a wider RST: more channel charge and overlap, its junction on FD
            net = ce.scale_in_subckt(net, c.pixel, "Xrst", "w", p["rst_w_factor"])
            for key in ("ad", "as", "pd", "ps"):
                net = ce.scale_in_subckt(net, c.pixel, "Xrst", key, p["rst_w_factor"])
        if el:
            net = ce.add_to_subckt(net, c.pixel, *el)
        net = _afe_edit(net, design, c, label, kind, p, colp, pattern, _J(op, m))
    if kind == "col_bridge":
        net = ce.add_top(net, Element("Rbridge", (cs[1].col, cs[2].col), p["r_bridge_ohm"]))
    if kind == "col_clamp":
        net = _clamp(net, design, nom, cs, p)
    if models:
        net = ce.add_top(net, models=tuple(models))
    return net, cs


def _variant(design, kind, p):
    """Uniform changes of the drawn devices."""
    dev = design.pixel.devices
    if kind == "sf_wl":
        return replace(design, pixel=replace(design.pixel, devices=replace(dev, sf_w=dev.sf_w * p["w_factor"],
                                                                           sf_l=dev.sf_l * p["l_factor"])))
    if kind == "load_gds":
        return replace(design, pixel=replace(design.pixel, devices=replace(
            dev, load_l=dev.load_l * p["l_factor"])))   # the bias mirrors it: the same current, less r_out
    return design


def _afe_edit(net, design, c, label, kind, p, colp, pattern, J):
    if kind == "afe_layout":
        f = colp[label]
        net = ce.scale_caps(net, c.afe, {"C11": f["C11"], "C12": f["C12"] * (1 + p["c12_rel"]),
                                         "C13": f["C13"] * (1 + p["c13_fringe_rel"])})
        net = ce.add_to_subckt(net, c.afe, Element("Cpvm", ("vm", "0"), p["cp_vm_rel"] * design.afe.c11))
    elif kind == "switch_injection":
        for sw in ("XSrefn", "XSrefp"):
            for key in ("w", "ad", "as", "pd", "ps"):
                net = ce.scale_in_subckt(net, c.afe, sw, key, p["vm_switch_w_factor"])
    elif kind == "afe_columns":
        f = colp[label]
        net = ce.scale_caps(net, c.afe, {"C11": f["c11"]})
        for sw in ("XSrefn", "XSrefp"):
            net = ce.scale_in_subckt(net, c.afe, sw, "w", f["sw"])
    elif kind == "column_fpn":
        net = ce.offset_gate(net, f"ld_{c.col}", colp[label]["dvt_V"])
    elif kind == "layout_light" and J > 0:
        t = _timing(design)[c.array]
        shares, total = pattern
        area = p["open_scale"] * total
        inner, top = [], []
        for k, (node, jk, share) in enumerate(shares):
            i = area * share * J
            pwl = ce.pulse(t.row(0), t.t_stop - ce.EDGE, i)
            if node in ("vm", "x", "c"):
                pins = ("vdd", node) if jk == "psd" else (node, "0")
                inner.append(Element(f"Ilo{k}", pins, pwl))
            else:
                n_ = c.col if node == "col" else f"in_{c.col}"
                pins = ("vdd", n_) if jk == "psd" else (n_, "0")
                top.append(Element(f"Ilo_{c.col}_{k}", pins, pwl))
        net = ce.add_to_subckt(net, c.afe, *inner) if inner else net
        net = ce.add_top(net, *top) if top else net
    return net


def _timing(design):
    from ..circuits.testbench import timings
    return timings(design, design.experiment.t_window)


def _clamp(net, design, nom, cs, p):
    from ..circuits.devices import mosfet
    for c in cs:
        arr = c.array
        v_lo = float(np.interp(p["clamp_at_frac"], np.linspace(0, 1, nom.v_sig[arr].size), nom.v_sig[arr]))
        net = ce.add_top(net, Element(f"Vcl_{c.col}", (f"cl_{c.col}", "0"), v_lo + 0.45),
                         mosfet(f"swc_{c.col}", c.col, c.rs, f"mc_{c.col}", "0", 1e-6, 0.35e-6, design.tech),
                         Element(f"Dcl_{c.col}", (f"cl_{c.col}", f"mc_{c.col}"), "dfault"),
                         models=(ce.DIODE,) if c.array == "primary" else ())
    return net


# ---- cases ----

def simulate_case(design, nom, kind: str, seed: int, backend: str = "batch", jobs=None,
                  pattern=None) -> tuple[list, dict]:
    """(rows, truth) of one case: its decks at each operating point's temperature, the set-up and noise.
    ``pattern``: the readout's open-junction pattern a ``layout_light`` case needs
    (``layout.pex.lightsilicon.light_pattern``: the layout sits above this module)."""
    from ..circuits.testbench import timings
    from ..measure.pixel import levels
    from .exact import simulate_exact
    g = np.random.default_rng(seed)
    k = KINDS[kind]
    p = k.draw(g, design)
    ops = operating_points(design, nom, g, k.campaign)
    limit_waits(design, nom, ops, kind, p)
    limit_exposures(design, nom, ops, kind, p)
    colp = column_draws(design, g, kind, p, ops)
    if kind == "layout_light" and not pattern:
        raise ValueError("a layout_light case needs the layout's open-junction pattern "
                         "(layout.pex.lightsilicon.light_pattern())")
    pattern = pattern if kind == "layout_light" else ()
    decks = [deck(design, nom, op, kind, p, colp, pattern, f"ood{seed}_{n}") for n, op in enumerate(ops)]
    kw = {"backend": backend} if jobs is None else {"backend": backend, "jobs": jobs}
    res = simulate_exact([d for d, _ in decks], **kw)
    setup = {pr: (1 + g.normal(0, SETUP_GAIN_SD), g.normal(0, SETUP_OFFSET_SD_V)) for pr in ("pixel", "afe")}
    tm = timings(design, design.experiment.t_window)
    rows = []
    for op, r, (_, cs) in zip(ops, res, decks):
        labels = [op["cols"]["primary"][0]] + op["cols"]["secondary"]
        for m, (c, col) in enumerate(zip(cs, labels)):
            arr = c.array
            v_pix = levels(r, c.col, tm[arr])[0]
            v_afe = float(r.at(c.out, tm[arr].t_reset_level(0)))
            for probe, v in (("pixel", v_pix), ("afe", v_afe)):
                rows.append({"array": arr, "row": op["row"], "col": col, "i_ph_A": _i(design, op, arr, chain=m),
                             "t_int_s": op["t_int"][arr], "t_wait_s": _t_wait(design, op, arr),
                             "temp_C": op["temp"], "probe": probe, "v_clean_V": v,
                             "i_ph_prev_A": _i(design, op, arr, prev=True, chain=m)})
    for row in rows:
        gain, offset = setup[row["probe"]]
        v = row.pop("v_clean_V")
        if kind == "setup_inl" and row["probe"] == "afe":
            v = v + p["bow_V"] * (1 - ((v - 1.75) / 0.45) ** 2)
        row["v_V"] = offset + gain * v + g.normal(0, NOISE_V / np.sqrt(N_AVG))
        row["v_std_V"], row["n_avg"] = NOISE_V, N_AVG
    truth = {"effect": k.expected, "circuit": kind, "params": p, "seed": seed, "campaign": k.campaign, "bench": "calibrated",
             "setup": {f"{kk}_{pr}": v for pr, (gn, off) in setup.items() for kk, v in (("gain", gn), ("offset_V", off))}}
    if pattern:
        truth["light_pattern"] = {"shares": [list(x) for x in pattern[0]], "open_area_m2": pattern[1]}
    return rows, truth


def plan_set(name: str, n_per_kind: int = 4, n_ool: int = 2, n_clean: int = 6) -> list:
    """(kind, seed) of a set's cases, round-robin over the kinds, seeds from ``SETS[name]``."""
    queues = [[k] * n_per_kind for k in IN_LIBRARY] + [[k] * n_ool for k in OUT_OF_LIBRARY] + [["none"] * n_clean]
    out = []
    while any(queues):
        for q in queues:
            if q:
                out.append((q.pop(), SETS[name] + len(out)))
    return out


def write_set(design, nom, name: str, pattern, folder: Path | None = None, plan=None, progress=None,
              jobs=None) -> dict:
    """Simulate a set's cases into ``folder`` (default ``OOD_DIR / name``), keeping the cases already there
    (``pattern``: ``layout.pex.lightsilicon.light_pattern()``)."""
    from .silicon import write_cases
    folder = Path(folder or OOD_DIR / name)
    return write_cases(design, nom, folder, plan or [(k, s) for k, s in plan_set(name)], progress, jobs, keep=True,
                       simulate=lambda d, n, kind, seed, jobs: simulate_case(d, n, kind, seed, jobs=jobs,
                                                                            pattern=pattern))


def stated_setup():
    """The calibration the sets' bench states (``--gain-sd 0.003 --offset-sd 0.002``)."""
    from .fit import SetupBounds
    return SetupBounds(gain_sd=SETUP_GAIN_SD, offset_sd_V=SETUP_OFFSET_SD_V)


def run_set(design, nom, name: str, folder: Path | None = None, only_ids=None) -> dict:
    """Diagnose a set's cases blind (with the calibration the bench states, ``stated_setup``) and score:
    top-1 and explained-when-right on the in-library kinds, "not explained" on the outside ones, ``none`` on
    the effect-free chips (``selftest.score``)."""
    from .diagnose import P_EXPLAINED, diagnose
    from .pvalue import chi2_sf
    from .selftest import score
    from .silicon import load_cases, table_of
    folder = Path(folder or OOD_DIR / name)
    cases, truths = load_cases(folder)
    out = []
    for cid, rows in cases.items():
        if only_ids is not None and cid not in only_ids:
            continue
        t = truths[cid]
        d = diagnose(design, table_of(design, rows, f"{folder.name}/cases.csv#{cid}"), nom, setup=stated_setup())
        nominal = next(r for r in d["ranking"] if r["effect"] == "none")
        p_none = chi2_sf(nominal["heldout_chi2_per_row"] * d["n_heldout"], d["n_heldout"] + d["n_calibration"])
        out.append({"case": cid, "truth": t["effect"], "circuit": t["circuit"], "accept": [t["effect"]],
                    "found": "+".join(sorted(d["effects"])), "explained": d["explained"],
                    "indistinguishable": d["indistinguishable"], "shrink": d["shrink_frac"],
                    "before_V": d["gap_before_rms_V"], "after_V": d["gap_after_rms_V"], "seed": t["seed"],
                    "campaign": t["campaign"], "verdict": d["verdict"],
                    # does the nominal model leave a gap beyond the noise? (an effect too small to see cannot be
                    # "not explained": the right answer to data the nominal model explains is none)
                    "gap_visible": bool(p_none < P_EXPLAINED)})
    r = score(out)
    outside = [c for c in out if c["truth"] == "out_of_library" and c["gap_visible"]]
    r["outside_visible"] = {"n": len(outside), "not_explained": sum(c["explained"] is False for c in outside)}
    r.update({"kind": f"out-of-distribution ({name})", "set": name, "noise_V": NOISE_V, "n_avg": N_AVG,
              "cases": out, "seeds": [min(c["seed"] for c in out), max(c["seed"] for c in out)] if out else None,
              "per_kind_explained": {k: float(np.mean([c["explained"] is True for c in out if c["circuit"] == k]))
                                     for k in sorted({c["circuit"] for c in out})}})
    return r
