"""The reference design of [Thesis2019]: the values it prints, and whether a design is that chip.

The report and ``pixelkit simulate`` compare a design with the dissertation only when the
comparison means something: when the design *is* its test chip in every value the
dissertation states (technology stand-in, photodiodes, pitches, array sizes, integration
times, readout clocks, swing, SF bias, the experiment's window and targets). Then the
comparison is a validation of the kit; for any other design it would be a figure of a chip
the user is not designing, so it is left out. Device sizes, the AFE and the mask opening are
not printed by the dissertation and do not take a design out of the comparison.

Where the kit departs from a stated value on purpose (``DEPARTURES``: the value it takes instead
and why; the reference design's settled read, designs/dual_pixel_revA.toml), a design at either value is the
chip, and the comparison names the departure beside the dissertation's figures.
"""
from __future__ import annotations

import math

#: The dissertation's values (table 3.2, the sizing text of chapter 3, appendix A).
THESIS = {
    "primary": {"array": "27 x 50", "pitch_um": 24.0, "pd": "15.1 x 13.55", "c_jdep_fF": 26.54, "cg_uV": 6.03,
                "fwc_ke": 248.0, "swing_V": 1.5, "f_read_kHz": 500.0},
    "secondary": {"array": "27 x 150", "pitch_um": 8.0, "pd": "5 x 5", "c_jdep_fF": 7.38, "cg_uV": 21.7,
                  "fwc_ke": 69.0, "swing_V": 1.5, "f_read_kHz": 1000.0, "mask_um2": 0.64},
    "c_a": 8.18, "c_c": 3.6, "i_mid_pA": 1400.0, "i_5pct_pA": 52.0, "c_m": 39.0,
}

#: (attribute path, value in SI) the reference design must have; technology by name.
_STATED = (
    ("primary.pd_width", 15.1e-6), ("primary.pd_height", 13.55e-6), ("primary.pitch", 24e-6),
    ("primary.rows", 27), ("primary.cols", 50), ("primary.t_int", 1e-3), ("primary.f_read", 500e3),
    ("secondary.pd_width", 5e-6), ("secondary.pd_height", 5e-6), ("secondary.pitch", 8e-6),
    ("secondary.rows", 27), ("secondary.cols", 150), ("secondary.t_int", 12e-3), ("secondary.f_read", 1e6),
    ("secondary_per_pixel", 3), ("pixel.swing", 1.5), ("pixel.sf_bias", 400e-9),
    ("experiment.t_window", 16e-6), ("experiment.mid_fraction", 0.5), ("experiment.low_fraction", 0.05),
)
TECHNOLOGY = "c35_thesis"
#: Stated values the kit departs from on purpose: (its value, why).
DEPARTURES = {
    "pixel.sf_bias": (1e-6, "column load 1 uA where the dissertation's simulations used ~400 nA: at 400 nA "
                            "the column with its AFE does not settle in the 1 MHz row of the secondary "
                            "(docs/timing-and-settling.md)"),
}


def _get(design, path: str):
    x = design
    for part in path.split("."):
        x = getattr(x, part)
    return x


def differences(design) -> list[str]:
    """The stated values in which ``design`` differs from the reference (empty: it is the reference)."""
    out = [] if getattr(design.tech, "name", None) == TECHNOLOGY else [f"technology {design.tech.name}"]
    for path, value in _STATED:
        got = _get(design, path)
        ok = [value] + ([DEPARTURES[path][0]] if path in DEPARTURES else [])
        if not any(math.isclose(float(got), float(v), rel_tol=1e-9, abs_tol=0.0) for v in ok):
            out.append(f"{path} {got:g}")
    return out


def departures(design) -> list[str]:
    """The ``DEPARTURES`` ``design`` takes, each as "path value: why"."""
    return [f"{path} {_get(design, path):g}: {why}" for path, (value, why) in DEPARTURES.items()
            if math.isclose(float(_get(design, path)), float(value), rel_tol=1e-9, abs_tol=0.0)]


def is_reference(design) -> bool:
    """Whether ``design`` is the dissertation's test chip in every value the dissertation states."""
    return not differences(design)
