"""The figures a ``[spec]`` entry can name: what each is, its unit, how the kit measures it.

Every figure is measured at one condition (process corner, temperature, supply) and,
for Monte Carlo, at one draw of the devices. Figures are SI inside (a charge in C, a
conversion gain in V/C, a fraction as a number); ``unit`` is how the sign-off table
shows it. ``group`` is the measurement that produces it (``verify.measure``); only the
groups the specs need are run. ``mc``: whether device mismatch moves it (figures
computed from the analytic C(V) model alone do not, so they get no yield).

``check`` names the independent path each figure is cross-checked against in the tests
and in ``docs/verify.md``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..units import parse_unit

KINDS = ("primary", "secondary")


@dataclass(frozen=True)
class Figure:
    name: str
    dim: str          # a pixelkit.units dimension name
    unit: str         # display unit
    group: str        # the measurement that produces it
    what: str
    check: str
    mc: bool = True
    #: (lo, hi) in SI, open: the values a real chip's figure can have. A spec limit outside it (or on
    #: its edge) always passes or always fails - "1e300 %", a minimum of 0 for a positive figure - and
    #: is refused when the design loads (issue 44).
    plausible: tuple = (0.0, math.inf)


def groups_of(figure_names, table: dict) -> list[str]:
    """The measurement groups the figures ``figure_names`` of ``table`` need (a figure's ``group`` may
    join several with '+'), each once, in the order first needed."""
    out = []
    for name in figure_names:
        for g in table[name].group.split("+"):
            if g not in out:
                out.append(g)
    return out


_Q = 1.602176634e-19   # C per electron
#: the range of each figure's values (SI, open interval); see Figure.plausible
PLAUSIBLE = {"conversion_gain": (1e-3 * 1e-6 / _Q, 1e4 * 1e-6 / _Q),     # 0.001 - 10,000 uV/e-
             "pd_conversion_gain": (1e-3 * 1e-6 / _Q, 1e4 * 1e-6 / _Q),
             "swing": (1e-6, 10.0),                          # 1 uV - 10 V
             "full_well": (1 * _Q, 1e9 * _Q),                 # 1 - 1e9 e-
             "read_noise": (1e-3 * _Q, 1e6 * _Q), "ktc_noise": (1e-3 * _Q, 1e6 * _Q),   # 0.001 - 1e6 e-
             "dynamic_range": (1.0, 1e10),                   # 0 - 200 dB
             "pd_dark_drop": (1e-9, 10.0), "settling": (1e-9, 10.0),   # 1 nV - 10 V
             "image_lag": (-1.0, 1.0),                        # -100 % - 100 % of the swing
             "gse": (1e-3, 1e12), "storage_light": (-1.0, 100.0), "criterion_secondary": (1e-6, 1.0), "afe_gain_error": (1e-9, 1.0),
             "power_pixel": (1e-15, 100.0), "power_column": (1e-15, 100.0), "power_chip": (1e-15, 100.0)}   # 1 fW - 100 W


def _per_kind(stem, dim, unit, group, what, check, mc=True):
    return [Figure(f"{stem}_{k}", dim, unit, group, what.format(kind=k), check, mc, PLAUSIBLE[stem]) for k in KINDS]


_LIST = [
    *_per_kind("conversion_gain", "V/C", "uV/e-", "pixel",
               "output-referred conversion gain of the {kind} subpixel, CG_out(0) in the report: double-sampled "
               "column signal per collected electron at a small signal (SPICE)",
               "analytic C(V) of PD + FD times the SF gain (physics.fd.response)"),
    *_per_kind("pd_conversion_gain", "V/C", "uV/e-", "pixel",
               "PD-referred conversion gain of the {kind} subpixel's PD node, CG_PD,node at the PD reset level in "
               "the report: drop of the PD node (junction and EC / TG diffusions) per collected electron during "
               "exposure, small signal (SPICE); thesis table 3.2's q / C_jdep is the bare junction's at 2.5 V",
               "analytic C(V) of the PD node (physics.subpixel.pd_node)"),
    *_per_kind("swing", "V", "V", "pixel",
               "column swing of the {kind} subpixel: saturated minus dark double-sampled signal (SPICE)",
               "pixel.swing minus the SF's drop (docs/pixel-model.md: 'Column swing ~0.85 V')"),
    *_per_kind("full_well", "C", "e-", "pixel",
               "full well at the column of the {kind} subpixel: column swing over the small-signal output-"
               "referred conversion gain (SPICE), the charge at which the column output saturates (not EMVA "
               "1288's saturation capacity, which the virtual camera reads off its photon transfer, nor table "
               "3.2's 1.5 V x C_jdep of the PD)",
               "the dark column level from the follower's operating point over A_sf q / C_total "
               "(tests/test_spec_limits.py)"),
    *_per_kind("read_noise", "C", "e-", "noise",
               "temporal read noise of the {kind} subpixel through the AFE ('read noise with the AFE' in the "
               "report), input-referred through CG_out(0) (kTC, NCDS, SF and load thermal and 1/f, dark shot, AFE; "
               "the SF gain from SPICE at the condition; with afe.opamp = \"ota\" the op-amp's terms are still "
               "the macromodel's noise_r / noise_corner)",
               "ngspice .noise of the read chain (camera.spicenoise)"),
    *_per_kind("ktc_noise", "C", "e-", "noise",
               "FD reset (kT/C) noise of the {kind} subpixel's NCDS read, input-referred electrons",
               "sqrt(k T C_FD) / q with C_FD from the junction model", mc=False),
    *_per_kind("dynamic_range", "1", "dB", "pixel+noise",
               "dynamic range of the {kind} subpixel: 20 log10(full well / read noise)",
               "the two figures it is made of"),
    *_per_kind("pd_dark_drop", "V", "mV", "dark",
               "drop of the {kind} PD node in the dark over its integration time t_int (its dark current; "
               "SPICE: the diode card's dark current and the EC/TG junction leakage)",
               "physics.dark.dark_current x t_int / C(V) of the PD node"),
    *_per_kind("image_lag", "1", "%", "lag",
               "image lag of the {kind} subpixel: a dark frame after a saturated one minus a dark frame after "
               "a dark one, each from the state its previous frame ended in, in % of the swing (SPICE)",
               "a hard reset leaves ~0; a deliberately soft reset shows lag (tests)"),
    *_per_kind("gse", "1", "", "gse",
               "global-shutter efficiency of the {kind} subpixel on the signal: signal per second of "
               "exposure over signal per second of storage under the same light (1 / PLS) (SPICE)",
               "pixel.gse x C_FD / (C_PD,node + C_FD) (physics.fd.signal_gse)"),
    *_per_kind("storage_light", "1", "%", "storage+pixel",
               "storage-node light of the {kind} array over a frame's readout: the double-sampled signal FD adds "
               "while the last row waits ((rows - 1) row times), in % of the column swing, under a source "
               "light.source_factor x the background (the sizing's background photocurrent of the subpixel) lit "
               "only then (an LED headlight's PWM off during the exposure); FD collects the photodiode's "
               "photocurrent over the GSE (pixel.gse, or the collection model's with light.model = \"modelled\") "
               "(SPICE)",
               "A_sf I_FD t / C_FD over the swing (physics.fd.storage_signal; tests/test_light_model.py)", mc=False),
    *_per_kind("settling", "V", "mV", "settling",
               "settling error of the {kind} array: worst |double-sampled signal - that of the same read with "
               "S1 and S2 four row times longer| over a 2-row dual column with its AFE (SPICE, chip.settling)",
               "the long read's own convergence (a twice longer read within 0.1 mV; tests/test_settling.py)",
               mc=False),
    Figure("criterion_secondary", "1", "%", "pixel",
           "the 5 % / mid-scale criterion of [Thesis2019]: the secondary's signal, in % of its swing, when the primary sits at "
           "mid_fraction of its swing under the same light (mask opening and integration times as designed; "
           "the thesis's equivalent-current method)",
           "i_mid / i_5pct of the thesis experiment (experiments.thesis)"),
    Figure("afe_gain_error", "1", "%", "afe",
           "gain error of the SC AFE: |(measured dVout / dVin) / (C11 / C13) - 1| (SPICE, three input steps)",
           "finite-gain charge balance eps / (1 + eps) (measure.afe)"),
    Figure("power_pixel", "W", "nW", "power",
           "average power of one dual pixel over a frame at the design's frame rate: its resets and its read "
           "current (the column load's current while its row is selected) (SPICE supply currents)",
           "bias currents x supply x duty (verify.power.estimate)"),
    Figure("power_column", "W", "uW", "power",
           "average power of one primary column's circuits: bias reference and AFE (op-amp, reference, "
           "samplers) (SPICE supply currents)", "bias currents x supply (verify.power.estimate)"),
    Figure("power_chip", "W", "mW", "power",
           "average power of the chip over a frame at the design's frame rate: resets, read currents, column "
           "bias and AFEs of both arrays (SPICE supply currents per block x counts; the control signals, "
           "which the thesis's FPGA drove, are left out)",
           "bias currents x supply x duty (verify.power.estimate)"),
]

FIGURES: dict[str, Figure] = {f.name: (f if f.name not in PLAUSIBLE else
                                       Figure(**{**f.__dict__, "plausible": PLAUSIBLE[f.name]})) for f in _LIST}

#: The figures of a pixel read by role with true CDS (the ``pixel4t`` and ``netlist`` families,
#: ``rolepix.measure``): one pixel kind, so no _primary / _secondary. Groups are ``rolepix``'s.
ROLE_FIGURES: dict[str, Figure] = {f.name: f for f in (
    Figure("conversion_gain", "V/C", "uV/e-", "signal",
           "output-referred conversion gain: the CDS output (SHR - SHS held on the column's sample-and-hold "
           "capacitors) per transferred electron at a small signal, a known photo-charge against a dark frame "
           "(SPICE)", "q A_sf A_sh / C_FD of the FD's devices (rolepix.model)", True, PLAUSIBLE["conversion_gain"]),
    Figure("full_well", "C", "e-", "signal",
           "full well at the CDS output: the saturated CDS output over the small-signal conversion gain "
           "(SPICE): the smaller of what the photodiode holds and what FD and the column can swing",
           "C_PPD V_pin of the pinned photodiode (physics.ppd) and FD's swing (rolepix.model)", True,
           PLAUSIBLE["full_well"]),
    Figure("read_noise", "C", "e-", "signal+noise",
           "temporal read noise of the true-CDS read, input-referred through the conversion gain: ngspice "
           ".noise of the read chain at the sample-and-hold node weighted by the CDS difference "
           "2 (1 - cos 2 pi f dt), plus the sample-and-hold capacitors' kT/C of both samples",
           "transient noise: the same read in the time domain with each device's noise as a source "
           "(rolepix.trnoise)", True, PLAUSIBLE["read_noise"]),
    Figure("image_lag", "1", "%", "lag",
           "image lag: the CDS output of a dark frame after a frame at 50 % of the full well, minus that of a "
           "dark frame after a dark one, in % of the bright frame's signal (SPICE)",
           "the thermionic-emission residual of physics.ppd over both transfers", True, PLAUSIBLE["image_lag"]),
    Figure("dark_current", "A", "e-/s", "signal+dark",
           "dark signal rate at the CDS output over the design's integration time: (dark CDS at t_int - dark "
           "CDS at the shortest exposure) / conversion gain / (t_int - shortest) (SPICE; the photodiode's "
           "generation and diffusion currents)", "I_gen + I_dif of physics.ppd at the temperature", True,
           (1e-25, 1e-6)),
    Figure("prnu", "1", "%", "prnu",
           "photo-response non-uniformity at 50 % of the full well: the spread (sigma / mean) of the CDS signal "
           "over the Monte Carlo's device draws (mismatch of RST, SF, RS, the column) at the nominal condition",
           "sigma of A_sf and C_FD from Pelgrom's law", False, (1e-9, 1.0)),
    Figure("power_chip", "W", "mW", "power",
           "average power of the array read at the design's frame rate: the column loads and their bias "
           "mirror while rows are read, the pixel resets (SPICE supply current over a row x columns)",
           "bias currents x supply (rolepix.power)", False, PLAUSIBLE["power_chip"]),
)}


def unit_scale(unit: str, dim: str) -> tuple[str, float] | None:
    """(kind, scale) to show an SI value of ``dim`` in ``unit``: kind "dB" (20 log10), "%"
    (x 100) or "lin" (divide by scale); None when the unit does not fit the dimension."""
    if dim == "1":
        return {"": ("lin", 1.0), "dB": ("dB", 1.0), "%": ("%", 1.0)}.get(unit)
    from ..units import DIMENSIONS
    try:
        scale, vec = parse_unit(unit)
    except ValueError:
        return None
    return ("lin", scale) if vec == DIMENSIONS[dim][0] else None


def shown(x: float, unit: str, dim: str) -> float:
    """``x`` (SI) in ``unit``."""
    kind, scale = unit_scale(unit, dim)
    if kind == "dB":
        return 20.0 * math.log10(x) if x > 0 else -math.inf
    if kind == "%":
        return 100.0 * x
    return x / scale


def units_for(dim: str) -> str:
    """Examples of units that fit ``dim`` (for error messages)."""
    return {"V/C": "uV/e-, V/C", "C": "e-, ke-, fC", "V": "V, mV, uV", "W": "W, mW, uW",
            "1": "a plain number, % or dB"}.get(dim, dim)
