"""Virtual silicon: measured-like data made by ngspice, with effects inserted as circuit elements.

Each case is a small lab campaign of ``N_OP`` operating points; each operating
point is ONE full-chain deck of the reference design (dual pixel: the primary
and three secondary subpixels, their column loads, S1X/S2X and one SC AFE per
column), so a deck gives eight rows (four columns x pixel / AFE probe). The
operating point's conditions (integration time, irradiance, wait before
readout, temperature, previous frame) enter the deck as the charges and
currents they imply; the effect enters as circuit elements (``INSERT``):

- ``gse``: a current pulse on each FD during its hold, proportional to the
  subpixel's irradiance x the wait (stray light on the storage node);
- ``fd_leakage``: the same element in the dark, with its temperature law;
- ``dark_current``: a DC current source on each PD (T law, area/perimeter);
- ``charge_injection``: a coupling capacitor from the RST clock line to FD and
  from the AFE's p1 clock to its virtual-ground node vm;
- ``sf_gain``: a conductance, switched in with the row select, from each
  column line to a source at the column's reset level (a chain gain loss that
  pivots at the reset level);
- ``afe_gain``: a capacitor in parallel with C13 (mismatched capacitors);
- ``readout_light``: a junction photocurrent on each AFE's vm node,
  proportional to the irradiance of the pixel it reads, either sign, while the
  AFE is clocked (the deck clocks it only during its row; a real AFE resets
  its nodes every row, so only the hold within the row matters);
- ``crosstalk``: extra current on the secondary PDs, irradiance x masked area;
- ``lag``: extra PD charge, a fraction of the previous frame's;
- ``column_pixel``: mismatched column-load transistor widths;
- ``column_afe``: mismatched C11 and a per-column clock coupling capacitor;
- out of library (the right answer is "not explained"): ``col_clamp`` (a
  diode, switched in with the row select, clamping the column line: a compressive output nonlinearity), ``col_bridge`` (a resistive bridge
  between two secondary columns), ``fd_pullup`` (a leak from FD to the supply,
  level dependent, no temperature law).

Temperatures enter only through the effects' T laws and the design's dark
current law (the deck runs at the design temperature, as the nominal
surrogate does). The simulated levels get the test set-up's gain and offset
and Gaussian noise of ``NOISE_V / sqrt(N_AVG)``, stated in the file. Parameter
ranges are written below (typical magnitudes of a 0.35 um 3.3 V pixel).
"""
from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from ..circuits.devices import mosfet
from ..circuits.testbench import dual_pixel_bench, timings
from ..fileio import write_atomic
from ..measure.pixel import levels
from ..spice.netlist import Element
from . import circuit_edits as ce
from .chains import edge_resolved
from .nominal import ARRAYS

N_OP = 7
NOISE_V = 0.6e-3
N_AVG = 4
# the bench of the cases added after the first 151: each probe's gain and offset drawn around 1 and 0 with these
# standard deviations, which that bench states as its calibration (``stated_setup``)
BENCH_GAIN_SD = 0.003
BENCH_OFFSET_SD_V = 0.002
SUBS = ("primary", "s0", "s1", "s2")
CASES_DIR = Path(__file__).with_name("silicon_cases")
IN_LIBRARY = ("gse", "fd_leakage", "dark_current", "charge_injection", "sf_gain", "afe_gain", "readout_light",
              "crosstalk", "lag", "column_pixel", "column_afe")
OUT_OF_LIBRARY = ("col_clamp", "col_bridge", "fd_pullup")
HEADER = ("case", "array", "row", "col", "i_ph_A", "t_int_s", "t_wait_s", "temp_C", "probe", "v_V", "v_std_V",
          "n_avg", "i_ph_prev_A")


def _sign(g):
    return float(g.choice([-1.0, 1.0]))


# effect -> function(rng) -> dict of circuit-element parameters (SI)
RANGES = {
    "gse": lambda g: {"pls": 1.0 / g.uniform(300, 10000)},
    "fd_leakage": lambda g: {"i_fd_A": g.uniform(5e-17, 5e-16), "diff_share": g.uniform(0.0, 0.6),
                             "dea_eV": g.uniform(-0.05, 0.1)},
    "dark_current": lambda g: {"i_d_A": g.uniform(2e-16, 2e-15), "diff_share": g.uniform(0.0, 0.6),
                               "dea_eV": g.uniform(-0.05, 0.1)},
    "charge_injection": lambda g: {"c_rst_fd_F": g.uniform(3e-18, 3e-17), "c_p1_vm_F": g.uniform(0.3e-15, 3e-15)},
    "sf_gain": lambda g: {"r_col_ohm": g.uniform(6e6, 2.5e7)},           # 3 - 10 % chain gain loss
    "afe_gain": lambda g: {"dc13_F": g.uniform(0.01, 0.05) * 500e-15},
    "readout_light": lambda g: {"a_junction_m2": _sign(g) * g.uniform(3e-11, 3e-10)},   # 0.7 - 7 mV on the secondary AFE
    "crosstalk": lambda g: {"k_xt": g.uniform(0.003, 0.03)},
    "lag": lambda g: {"lag": g.uniform(0.01, 0.05)},
    "column_pixel": lambda g: {"load_w_rel_sd": g.uniform(0.02, 0.08)},
    "column_afe": lambda g: {"c11_rel_sd": g.uniform(0.003, 0.01), "c_clk_sd_F": g.uniform(0.3e-15, 1.5e-15)},
    "col_clamp": lambda g: {"clamp_at_frac": g.uniform(0.35, 0.6)},
    # added later (ADDED_KINDS): uniform changes of the whole chip, and the columns' Monte Carlo mismatch
    "load_current": lambda g: {"bias_rel": _sign(g) * g.uniform(0.05, 0.2)},     # column load current
    "sf_size": lambda g: {"sf_w_factor": float(np.exp(g.uniform(np.log(0.6), np.log(1.6))))},
    "c11_ratio": lambda g: {"c11_rel": _sign(g) * g.uniform(0.01, 0.05)},        # C11 / C13 ratio
    "opamp_gain": lambda g: {"gain": 10 ** (g.uniform(30.0, 50.0) / 20)},        # DC gain 30 - 50 dB (60 designed)
    "mc_columns": lambda g: {},                                                  # library Pelgrom draws per column
    "col_bridge": lambda g: {"r_bridge_ohm": g.uniform(1e5, 4e5)},
    "fd_pullup": lambda g: {"r_pullup_ohm": g.uniform(2e14, 1e15)},
}


def junction_law(p: dict, temp_C: float) -> float:
    """The leakage laws of the cases' dark current and FD leakage: I(T) / I(25 degC) of a junction whose
    generation current (~ n_i, its activation energy moved by ``dea_eV``) and diffusion current (~ n_i^2, the
    share ``diff_share`` at 25 degC) add, n_i of silicon with the BSIM4 band gap - the law the effect library
    fits (``effects._junction``): these cases are in its distribution by construction. (Until the effect
    library carried the junction's law, they doubled every 5 - 9 K at any temperature: 1.4 eV near 85 degC,
    beyond silicon's band gap.)"""
    from ..constants import K_B, Q
    from ..physics.dark import bandgap
    t, t0 = temp_C + 273.15, 298.15
    kq = K_B / Q
    ni = (t / t0) ** 1.5 * np.exp((bandgap(t0) / t0 - bandgap(t) / t) / (2 * kq))
    gen = ni * np.exp(-p["dea_eV"] / kq * (1 / t - 1 / t0))
    return float((1 - p["diff_share"]) * gen + p["diff_share"] * ni * ni)


def operating_points(design, nom, g, campaign: str = "lab") -> list[dict]:
    """Lab-like operating points (one deck each) of a ``CAMPAIGNS`` kind."""
    c = CAMPAIGNS[campaign]
    (t_lo, t_hi), (f_lo, f_hi) = c["t_int"], c["light"]
    ops = []
    for k in range(c["points"]):
        t_int = float(np.exp(g.uniform(np.log(t_lo), np.log(t_hi))))
        row = int(g.integers(0, c.get("rows", design.primary.rows)))
        extra = float(g.choice(c.get("extra_wait", [0.0, 10e-3, 40e-3])))
        temp = float(g.choice(c["temps"]))
        dark = g.random() < c["dark"]
        i = {}
        for s in SUBS:
            arr = "primary" if s == "primary" else "secondary"
            frac = 0.0 if dark else g.uniform(f_lo, f_hi)
            i[s] = frac * nom.q_grid[arr][-1] / t_int
        ops.append({"t_int": t_int, "row": row, "extra_wait": extra, "temp": temp, "i": i,
                    "i_prev": {s: i[s] * g.uniform(0.0, 2.0) for s in SUBS}, "col_p": k % 3})
    return ops


# campaign -> operating points, t_int range (s), temperatures (degC), dark-frame probability, light as a fraction
# of the full-well charge (and optionally: rows to draw from, extra waits). "lab": the committed set's; "rich":
# 10 points, a quarter dark (two effects at once); "dark_hot": long, hot, mostly dark exposures (what a lab takes
# to measure dark current); "one_condition": one integration time, temperature and wait (a set that cannot tell
# the laws of t_int, T and t_wait apart: the bad-input check)
CAMPAIGNS = {"lab": {"points": N_OP, "t_int": (50e-6, 2e-3), "temps": (25.0, 45.0, 65.0), "dark": 0.12,
                     "light": (0.03, 0.6)},
             "rich": {"points": 10, "t_int": (50e-6, 2e-3), "temps": (25.0, 45.0, 65.0), "dark": 0.25,
                      "light": (0.03, 0.6)},
             "dark_hot": {"points": 10, "t_int": (2e-3, 50e-3), "temps": (45.0, 65.0, 85.0), "dark": 0.5,
                          "light": (0.02, 0.3)},
             "one_condition": {"points": 3, "t_int": (2e-3, 2e-3), "temps": (65.0,), "dark": 0.0,
                               "light": (0.02, 0.3), "rows": 1, "extra_wait": [10e-3]}}


FD_LIMIT = 0.25     # storage-node charge kept below this fraction of the FD's own swing


def wait_steps(op) -> list:
    """The extra waits a lab tries when the storage node overflows, longest first, none above the point's own."""
    return [w for w in (op["extra_wait"], 10e-3, 2e-3, 0.0) if w <= op["extra_wait"]]


def limit_waits(design, nom, ops, effect, p) -> None:
    """Shorten an operating point's extra wait until the storage-node charge stays in range.

    A lab does the same: a wait that drives the FD out of its swing measures nothing.
    """
    if effect not in ("gse", "fd_leakage"):
        return
    for op in ops:
        for extra in wait_steps(op):
            op["extra_wait"] = extra
            ok = True
            for s in SUBS:
                arr = _arr(s)
                tw = _t_wait(design, op, arr)
                if effect == "gse":
                    q = p["pls"] * op["i"][s] / getattr(design, arr).photoactive_area * design.primary.photoactive_area * tw
                else:
                    q = p["i_fd_A"] * junction_law(p, op["temp"]) * tw
                ok &= q * max(nom.fd_ratio[arr][1]) < FD_LIMIT * nom.q_grid[arr][-1]
            if ok:
                break


PD_LIMIT = 0.6     # PD charge (light + dark) kept below this fraction of the full-well charge


def limit_exposures(design, nom, ops, effect, p) -> None:
    """Halve an operating point's integration time until the PD charge stays in range (a lab shortens a
    hot dark exposure that would saturate): for the dark-current effect, whose T law can reach x 4000."""
    if effect != "dark_current":
        return
    from ..physics.dark import dark_current
    for op in ops:
        for _ in range(12):
            law = junction_law(p, op["temp"])
            worst = max((op["i"][s] + dark_current(*nom.dark[_arr(s)], op["temp"] + 273.15, nom.pd)
                         + p["i_d_A"] * law * (1.0 if s == "primary" else
                                               design.secondary.perimeter / design.primary.perimeter))
                        * op["t_int"] / nom.q_grid[_arr(s)][-1] for s in SUBS)
            if worst < PD_LIMIT:
                break
            op["t_int"] /= 2


def _t_wait(design, op, arr):
    f = design.primary.f_read if arr == "primary" else design.secondary.f_read
    return (op["row"] + 1) / f + op["extra_wait"]


def _arr(s):
    return "primary" if s == "primary" else "secondary"


def _col_of(s):
    return "col_p" if s == "primary" else f"col_{s}"


def _col_label(s, op):
    return op["col_p"] if s == "primary" else int(s[1])


def _columns(design, g, effect, p):
    """Per-column draws of the column effects, keyed by (array, column label)."""
    keys = [("primary", c) for c in range(3)] + [("secondary", c) for c in range(3)]
    out = {}
    if effect == "column_pixel":
        out = {k: {"w": 1 + g.normal(0, p["load_w_rel_sd"])} for k in keys}
    elif effect == "column_afe":
        out = {k: {"c11": 1 + g.normal(0, p["c11_rel_sd"]), "cc": abs(g.normal(0, p["c_clk_sd_F"])),
                   "line": str(g.choice(["p1", "p1b"]))} for k in keys}
    elif effect == "mc_columns":
        out = {k: _mc_column(design, g) for k in keys}
    return out


def _mc_column(design, g) -> dict:
    """One column's Monte Carlo draw, Pelgrom with the model library's own coefficients (``physics.pelgrom``):
    the load's threshold and current factor, C11 / C12 / C13 (the technology's capacitor matching) and
    the op-amp's input offset (drawn as the difference of an 8 / 1 um input pair's thresholds)."""
    from ..physics.pelgrom import cap_sigma_rel, sigma_beta, sigma_vth
    dev, a = design.pixel.devices, design.afe
    return {"dvt": float(g.normal(0, sigma_vth(design, dev.load_w, dev.load_l))),
            "dbeta": float(g.normal(0, sigma_beta(design, dev.load_w, dev.load_l))),
            "caps": {n: float(1 + g.normal(0, cap_sigma_rel(design, c))) for n, c in
                     (("C11", a.c11), ("C12", a.c12), ("C13", a.c13))},
            "vos": float(g.normal(0, np.sqrt(2) * sigma_vth(design, 8e-6, 1e-6)))}


def _variant(design, parts):
    """The design with the uniform changes of ``parts`` (a chip whose every column differs the same way)."""
    from dataclasses import replace
    for name, p in parts:
        if name == "load_current":
            design = replace(design, pixel=replace(design.pixel, sf_bias=design.pixel.sf_bias * (1 + p["bias_rel"])))
        elif name == "sf_size":
            dev = design.pixel.devices
            design = replace(design, pixel=replace(design.pixel, devices=replace(dev, sf_w=dev.sf_w * p["sf_w_factor"])))
        elif name == "c11_ratio":
            design = replace(design, afe=replace(design.afe, c11=design.afe.c11 * (1 + p["c11_rel"])))
        elif name == "opamp_gain":
            design = replace(design, afe=replace(design.afe, gain=p["gain"]))
    return design


def deck(design, nom, op, effect, p, colp, title):
    """The full-chain deck of one operating point with ``effect`` inserted (``a+b``: both)."""
    t_w = design.experiment.t_window
    from ..physics.dark import dark_current
    parts = _parts(effect, p)
    q = {}
    for s in SUBS:
        arr = _arr(s)
        area, per = nom.dark[arr]
        q[s] = (op["i"][s] + dark_current(area, per, op["temp"] + 273.15, nom.pd)) * op["t_int"]
    from dataclasses import replace
    at = replace(design, temperature=op["temp"] + 273.15) if op.get("device_temperature") else design
    net = dual_pixel_bench(_variant(at, parts), q["primary"] / t_w, tuple(q[s] / t_w for s in SUBS[1:]),
                           with_afe=True, title=title)
    net = edge_resolved(ce.specialise(net, design.secondary_per_pixel), design)
    for name, pe in parts:
        net = _insert(net, design, nom, op, name, pe, colp)
    return net


def _parts(effect, p) -> list:
    """[(effect, its parameters)]: one, or the two of a two-effect case ``a+b``."""
    if effect and "+" in effect:
        return [(e, p[e]) for e in effect.split("+")]
    return [(effect, p)]


def _insert(net, design, nom, op, effect, p, colp):
    """``effect`` as circuit elements in every chain of ``net``."""
    t_w = design.experiment.t_window
    law = junction_law(p, op["temp"]) if "diff_share" in p else 1.0
    for s in SUBS:
        arr, sub = _arr(s), ce.pixel_subckt(s)
        J = op["i"][s] / getattr(design, arr).photoactive_area
        tw = _t_wait(design, op, arr)
        el = []
        if effect == "gse":
            el.append(ce.fd_current(design, arr, p["pls"] * J * design.primary.photoactive_area * tw, s, "gse"))
        elif effect == "fd_leakage":
            el.append(ce.fd_current(design, arr, p["i_fd_A"] * law * tw, s, "leak"))
        elif effect == "dark_current":
            ratio = 1.0 if arr == "primary" else design.secondary.perimeter / design.primary.perimeter
            el.append(Element("Idk", ("pd", "0"), p["i_d_A"] * ratio * law * op["t_int"] / t_w))
        elif effect == "charge_injection":
            el.append(Element("Ccf", ("rst", "fd"), p["c_rst_fd_F"]))
        elif effect == "crosstalk" and arr == "secondary":
            el.append(Element("Ixt", ("pd", "0"), p["k_xt"] * J * design.secondary.area * op["t_int"] / t_w))
        elif effect == "lag":
            el.append(Element("Ilag", ("pd", "0"), p["lag"] * op["i_prev"][s] * op["t_int"] / t_w))
        elif effect == "fd_pullup":
            t0, t1 = ce.hold_window(design, arr)
            el.append(Element("Rpu", ("fd", "vdd"), p["r_pullup_ohm"] * (t1 - t0) / tw))
        if el:
            net = ce.add_to_subckt(net, sub, *el)
        col = _col_of(s)
        afe = f"scafe_{col}"
        if effect == "charge_injection":
            net = ce.add_to_subckt(net, afe, Element("Ccp", ("p1", "vm"), p["c_p1_vm_F"]))
        elif effect == "afe_gain":
            net = ce.add_to_subckt(net, afe, Element("Cdc13", ("vm", "c"), p["dc13_F"]))
        elif effect == "readout_light":
            net = ce.add_to_subckt(net, afe, ce.vm_current(design, arr, p["a_junction_m2"] * J))
        elif effect == "column_afe":
            c = colp[(arr, _col_label(s, op))]
            net = _scale_c11(ce.add_to_subckt(net, afe, Element("Ccc", (c["line"], "vm"), max(c["cc"], 1e-18))),
                             afe, c["c11"])
        elif effect == "column_pixel":
            net = ce.scale_load(net, col, colp[(arr, _col_label(s, op))]["w"])
        elif effect == "mc_columns":
            c = colp[(arr, _col_label(s, op))]
            net = ce.scale_load(ce.offset_gate(net, f"ld_{col}", c["dvt"]), col, 1.0 + c["dbeta"])
            net = _set_vos(ce.scale_caps(net, afe, c["caps"]), afe, c["vos"])
        elif effect == "sf_gain":   # connected while the row is selected
            net = ce.column_conductance(net, design, col, float(nom.v_rst[arr].mean()), 1.0 / p["r_col_ohm"])
        elif effect == "col_clamp":
            v_lo = float(np.interp(p["clamp_at_frac"], np.linspace(0, 1, nom.v_sig[arr].size), nom.v_sig[arr]))
            gate = "rs_p" if arr == "primary" else "rs_s"
            net = ce.add_top(net, Element(f"Vcl_{col}", (f"cl_{col}", "0"), v_lo + 0.45),
                             mosfet(f"swc_{col}", col, gate, f"mc_{col}", "0", 1e-6, 0.35e-6, design.tech),
                             Element(f"Dcl_{col}", (f"cl_{col}", f"mc_{col}"), "dfault"),
                             models=(ce.DIODE,) if s == "primary" else ())
    if effect == "col_bridge":
        net = ce.add_top(net, Element("Rbridge", ("col_s0", "col_s1"), p["r_bridge_ohm"]))
    return net


def _scale_c11(net, afe, factor):
    """Scale C11 of one AFE copy (a number, or the subcircuit's ``c11`` parameter default)."""
    return ce.scale_caps(net, afe, {"C11": factor})


def _set_vos(net, afe, vos):
    """The input offset of one AFE copy's op-amp macromodel (its ``vos`` parameter)."""
    from dataclasses import replace
    subs = tuple(replace(s, elements=tuple(replace(e, params=(*e.params, ("vos", vos))) if e.name == "Xop" else e
                                           for e in s.elements)) if s.name == afe else s for s in net.subckts)
    return replace(net, subckts=subs)


def simulate_case(design, nom, effect: str | None, seed: int, backend="batch", jobs=None,
                  campaign: str | None = None, edit=None, device_temperature: bool = False) -> tuple[list, dict]:
    """(rows as dicts, truth) of one case: its decks, noise and set-up added.

    ``campaign`` None: the committed set's first cases (campaign "lab", one set-up gain and offset for
    both probes, uniform +-2 % / +-20 mV). Otherwise (cases added later): that campaign and a set-up per
    probe, gain N(1, 0.3 %) and offset N(0, 2 mV), as a real bench. ``edit(net, op) -> net``: a further
    change of each deck (``layout.pex.lightsilicon``'s light on the layout's open junctions).
    ``device_temperature``: every deck at its operating point's temperature (the committed cases ran at the
    design temperature, the effects' laws alone following ``temp_C``: ``run_committed`` diagnoses them with
    the surrogate's levels at the design temperature, ``Nominal.at_design_temperature``)."""
    from ..spice import simulate_many
    g = np.random.default_rng(seed)
    ops = operating_points(design, nom, g, campaign or "lab")
    for op in ops:
        op["device_temperature"] = device_temperature
    parts = [e for e in effect.split("+")] if effect else []
    p = RANGES[effect](g) if effect and len(parts) == 1 else {e: RANGES[e](g) for e in parts}
    for name, pe in _parts(effect, p):
        limit_waits(design, nom, ops, name, pe)
        if campaign is not None:
            limit_exposures(design, nom, ops, name, pe)
    colp = {}
    for name, pe in _parts(effect, p):
        colp.update(_columns(design, g, name, pe))
    nets = [deck(design, nom, op, effect, p, colp, f"si{seed}_{k}") for k, op in enumerate(ops)]
    nets = nets if edit is None else [edit(n, op) for n, op in zip(nets, ops)]
    kw = {"backend": backend} if jobs is None else {"backend": backend, "jobs": jobs}
    if campaign is None:
        res = simulate_many(nets, **kw)
    else:   # added cases: every deck at the kit's tolerances (a retried deck moved levels by mV)
        from .exact import simulate_exact
        res = simulate_exact(nets, **kw)
    if campaign is None:
        gain, offset = 1 + g.uniform(-0.02, 0.02), g.uniform(-0.02, 0.02)
        setup = {"pixel": (gain, offset), "afe": (gain, offset)}
    else:
        setup = {pr: (1 + g.normal(0, BENCH_GAIN_SD), g.normal(0, BENCH_OFFSET_SD_V)) for pr in ("pixel", "afe")}
    tm = timings(design, design.experiment.t_window)
    rows = []
    for op, r in zip(ops, res):
        for s in SUBS:
            arr, col = _arr(s), _col_of(s)
            v_pix = levels(r, col, tm[arr])[0]
            v_afe = float(r.at(f"out_{col}", tm[arr].t_reset_level(0)))
            for probe, v in (("pixel", v_pix), ("afe", v_afe)):
                rows.append({"array": arr, "row": op["row"], "col": _col_label(s, op), "i_ph_A": op["i"][s],
                             "t_int_s": op["t_int"], "t_wait_s": _t_wait(design, op, arr), "temp_C": op["temp"],
                             "probe": probe, "v_clean_V": v, "i_ph_prev_A": op["i_prev"][s]})
    for row in rows:
        gain, offset = setup[row["probe"]]
        row["v_V"] = offset + gain * row.pop("v_clean_V") + g.normal(0, NOISE_V / np.sqrt(N_AVG))
        row["v_std_V"], row["n_avg"] = NOISE_V, N_AVG
    truth = {"effect": _expected(effect), "circuit": effect or "none", "params": p, "seed": seed}
    if campaign is None:
        truth.update({"setup_gain": setup["pixel"][0], "setup_offset_V": setup["pixel"][1]})
    else:
        truth.update({"campaign": campaign, "accept": ACCEPT.get(effect, [_expected(effect)]),
                      "setup": {f"{k}_{pr}": v for pr, (gn, off) in setup.items()
                                for k, v in (("gain", gn), ("offset_V", off))}})
    return rows, truth


# the library effect a circuit change should be named as (a circuit of the library's own name: that name)
EXPECTED = {"load_current": "column_load", "sf_size": "sf_strength", "c11_ratio": "afe_gain",
            "opamp_gain": "afe_gain", "mc_columns": "column_pixel"}
ACCEPT = {"mc_columns": ["column_pixel", "column_afe"]}   # real per-column mismatch: either per-column stage


def _expected(effect):
    if effect is None:
        return "none"
    if effect in OUT_OF_LIBRARY:
        return "out_of_library"
    return "+".join(sorted(EXPECTED.get(e, e) for e in effect.split("+")))


def plan_cases(n_per_effect=9, n_readout_light=12, n_ool_per_kind=7, n_clean=20, n_more_readout_light=8,
               seed0=1000) -> list[tuple[str | None, int]]:
    """(effect, seed) of every committed case, interleaved round-robin over the kinds; then
    ``n_more_readout_light`` readout-light cases (added later, for a finer figure of the documented
    failure; same ranges and campaign, the seeds continue)."""
    queues = [[e] * (n_readout_light if e == "readout_light" else n_per_effect) for e in IN_LIBRARY]
    queues += [[e] * n_ool_per_kind for e in OUT_OF_LIBRARY] + [[None] * n_clean]
    out = []
    while any(queues):
        for q in queues:
            if q:
                out.append((q.pop(), seed0 + len(out)))
    out += [("readout_light", seed0 + len(out) + k) for k in range(n_more_readout_light)]
    out += plan_added(seed0 + len(out))
    return out + plan_clean_bench(seed0 + len(out))


UNIFORM = ("load_current", "sf_size", "c11_ratio", "opamp_gain")
PAIRS = (("gse+fd_leakage", "rich"), ("sf_gain+afe_gain", "rich"), ("lag+crosstalk", "rich"),
         ("dark_current+fd_leakage", "dark_hot"))


def plan_added(seed0: int, n_uniform=9, n_mc=9, n_dark=9, n_pair=5) -> list[tuple]:
    """(effect, seed, campaign) of the cases added after the first 151 (seeds continue from ``seed0``,
    interleaved round-robin): each uniform change, the columns' Monte Carlo mismatch, dark current in a
    campaign of long hot dark exposures, and two effects at once."""
    queues = [[(e, "lab")] * n_uniform for e in UNIFORM] + [[("mc_columns", "lab")] * n_mc]
    queues += [[("dark_current", "dark_hot")] * n_dark] + [[pc] * n_pair for pc in PAIRS]
    out = []
    while any(queues):
        for q in queues:
            if q:
                e, c = q.pop()
                out.append((e, seed0 + len(out), c))
    return out


def plan_clean_bench(seed0: int, n_clean=20) -> list[tuple]:
    """(None, seed, "lab") of the effect-free chips measured on the calibrated bench, added after the cases of
    ``plan_added``: with the bench's calibration stated, the diagnosis must still answer ``none`` there."""
    return [(None, seed0 + k, "lab") for k in range(n_clean)]


def _fmt(v):
    return f"{v:.9g}" if isinstance(v, float) else str(v)


def write_cases(design, nom, folder: Path = CASES_DIR, plan=None, progress=None, jobs=None,
                keep: bool = False, simulate=None) -> dict:
    """Simulate every planned case; write ``cases.csv`` (all rows, ``case`` column) and ``truth.json``.

    Both files are rewritten (atomically) after every case, so an interrupted run
    leaves the cases done so far, consistent. ``keep``: the folder's cases stay as
    they are and only planned cases it does not hold are simulated and added.
    ``simulate(design, nom, kind, seed, jobs) -> (rows, truth)``: another generator's case
    (``ood.simulate_case``); default this module's.
    """
    plan = plan or plan_cases()
    buf = io.StringIO()
    w = csv.writer(buf)
    truths = {}
    from ..fileio import out_folder
    folder = out_folder(Path(folder), root=True)   # checked: a device, a file or a dangling link is refused
    if keep and (folder / "truth.json").exists():
        truths = json.loads((folder / "truth.json").read_text())
        with open(folder / "cases.csv", newline="") as fh:   # as written (csv's \r\n rows)
            buf.write(fh.read())
    else:
        w.writerow(HEADER)
    for k, (effect, seed, *campaign) in enumerate(plan):
        cid = f"c{seed}"
        if cid in truths:
            continue
        if simulate is None:
            rows, truth = simulate_case(design, nom, effect, seed, jobs=jobs, campaign=(campaign or [None])[0])
        else:
            rows, truth = simulate(design, nom, effect, seed, jobs)
        truths[cid] = truth
        for r in rows:
            w.writerow([cid] + [_fmt(r[h]) for h in HEADER[1:]])
        write_atomic(folder / "cases.csv", buf.getvalue())
        write_atomic(folder / "truth.json", json.dumps(truths, indent=1, sort_keys=True))
        if progress:
            progress(k + 1, len(plan))
    return {"n_cases": len(truths), "folder": str(folder)}


def load_cases(folder: Path = CASES_DIR) -> tuple[dict, dict]:
    """{case id: list of row dicts} and the truths of the committed cases."""
    folder = Path(folder)
    truths = json.loads((folder / "truth.json").read_text())
    cases: dict = {}
    with open(folder / "cases.csv", newline="") as fh:
        for r in csv.DictReader(fh):
            cases.setdefault(r.pop("case"), []).append(r)
    return cases, truths


def table_of(design, rows, source):
    """A validated ``Table`` from committed row dicts (the same checks a user's file gets)."""
    from .data import validate
    header = list(rows[0])
    return validate(header, rows, design, True, source)


def stated_setup(truth: dict):
    """The test set-up a case's bench states, as a user passes it (``--gain-sd`` / ``--offset-sd``): the cases
    added after the first 151 come from a calibrated bench (gain and offset per probe within ``BENCH_GAIN_SD``
    / ``BENCH_OFFSET_SD_V``); the first 151 from a bench with a gain within +-2 % and an offset within +-20 mV
    and no calibration (the default tolerances hold it)."""
    from .fit import SetupBounds
    from .selftest import bench
    if bench(truth) == "free":
        return SetupBounds()
    return SetupBounds(gain_sd=BENCH_GAIN_SD, offset_sd_V=BENCH_OFFSET_SD_V)


def run_committed(design, nom, folder: Path = CASES_DIR, only=None, only_ids=None, jobs: int = 1) -> dict:
    """Diagnose every committed SPICE case (blind; ``only``: these kinds, ``only_ids``: these cases), each with
    the set-up its bench states (``stated_setup``), against the surrogate's levels at the design temperature
    (the decks' own, ``simulate_case``); score. ``jobs`` > 1: the cases shared out over that many processes
    (each case's diagnosis is independent of the others'; the answers are the same as in one)."""
    from .selftest import score
    cases, truths = load_cases(folder)
    nom = nom.at_design_temperature()      # the committed decks ran at the design temperature
    ids = [cid for cid in cases if not (only and truths[cid]["effect"] not in only)
           and not (only_ids is not None and cid not in only_ids)]
    if jobs > 1 and len(ids) > 1:
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor
        with ProcessPoolExecutor(max_workers=jobs, mp_context=mp.get_context("spawn")) as pool:
            parts = list(pool.map(_diagnose_committed, [(design, nom, folder, ids[k::jobs]) for k in range(jobs)]))
        order = {cid: i for i, cid in enumerate(ids)}
        out = sorted((c for part in parts for c in part), key=lambda c: order[c["case"]])
    else:
        out = _diagnose_committed((design, nom, folder, ids), (cases, truths))
    r = score(out)
    r.update({"kind": "SPICE-generated", "noise_V": NOISE_V, "n_avg": N_AVG, "cases": out,
              "seeds": [min(c["seed"] for c in out), max(c["seed"] for c in out)] if out else None,
              **by_class(out)})
    return r


def _diagnose_committed(job, loaded=None) -> list:
    """The answers to the committed cases ``ids`` of ``folder`` (``job``: design, nominal at the design
    temperature, folder, ids), one dict each."""
    from .diagnose import diagnose
    from .selftest import bench
    design, nom, folder, ids = job
    cases, truths = loaded or load_cases(folder)
    out = []
    for cid in ids:
        t = truths[cid]
        d = diagnose(design, table_of(design, cases[cid], f"{folder}/cases.csv#{cid}"), nom, setup=stated_setup(t))
        out.append({"case": cid, "truth": t["effect"], "circuit": t["circuit"],
                    "accept": t.get("accept", [t["effect"]]),
                    "found": "+".join(sorted(d["effects"])), "explained": d["explained"],
                    "indistinguishable": d["indistinguishable"], "shrink": d["shrink_frac"],
                    "before_V": d["gap_before_rms_V"], "after_V": d["gap_after_rms_V"], "seed": t["seed"],
                    "campaign": t.get("campaign", "lab"), "bench": bench(t),
                    "gap_visible": _gap_visible(d)})
    return out


def _gap_visible(d) -> bool:
    """Does the nominal model alone leave the held-out rows unexplained (p < P_EXPLAINED)? If not, the
    inserted change is within the noise and the set-up's gain / offset on these data: nothing to name."""
    from .diagnose import P_EXPLAINED
    from .pvalue import chi2_sf
    none = next(r for r in d["ranking"] if r["effect"] == "none")
    return bool(chi2_sf(none["heldout_chi2_per_row"] * d["n_heldout"], d["n_heldout"] + d["n_calibration"])
                < P_EXPLAINED)


def by_class(cases: list) -> dict:
    """The rates of the added kinds: uniform changes named per column, named right (all, and those whose data
    show a gap: the nominal model alone not explained), real column mismatch named per column, both of two
    effects named, dark current in long hot dark exposures, ``none`` on effect-free chips of the calibrated
    bench (its calibration stated)."""
    per_col = ("column_pixel", "column_afe")

    def rate(xs, fn):
        return {"rate": float(np.mean([fn(c) for c in xs])), "n": len(xs)} if xs else None
    uni = [c for c in cases if c["circuit"] in UNIFORM]
    return {"uniform_named_uniform": rate(uni, lambda c: c["found"] not in per_col),
            "uniform_named_right": rate(uni, lambda c: c["found"] in c["accept"]),
            "uniform_visible_named_right": rate([c for c in uni if c.get("gap_visible", True)],
                                                lambda c: c["found"] in c["accept"]),
            "mc_named_per_column": rate([c for c in cases if c["circuit"] == "mc_columns"],
                                        lambda c: c["found"] in per_col),
            "two_effects_both_named": rate([c for c in cases if "+" in c["circuit"]],
                                           lambda c: c["found"] == c["truth"]),
            "dark_current_hot_named": rate([c for c in cases if c["circuit"] == "dark_current"
                                            and c["campaign"] == "dark_hot"], lambda c: c["found"] == "dark_current"),
            "none_on_clean_calibrated": rate([c for c in cases if c["truth"] == "none" and c["bench"] == "calibrated"],
                                             lambda c: c["found"] == "none")}
