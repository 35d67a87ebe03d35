"""One name per figure in the report: the figures that exist in more than one definition.

A conversion gain, a read noise or a DSNU can be defined several ways (which capacitance,
at which bias, referred through which gain, which effects included); the report gives each
definition its own name, uses that name wherever the figure appears (``label``), and the
summary section lists them with their definitions (``glossary_rows``).
``tests/test_report_names.py`` checks that a name never carries two values in one report.
"""
from __future__ import annotations

#: name -> (unit as printed, definition, why it is a name of its own). Bias-dependent names are made by
#: ``cg_jdep`` / ``c_jdep`` / ``c_node`` / ``cg_node`` / ``fw_jdep`` / ``fw_jdep_cv``. The names of one
#: quantity (conversion gain, full well, read noise, DSNU) that are left after one definition per name:
#: each is kept because it answers a different question, said in its third field.
GLOSSARY = {
    "C_jdep(V)": ("fF", "capacitance of the PD junction alone (area and perimeter terms) at reverse bias V",
                  "[Thesis2019] table 3.2 sizes the junction alone"),
    "C_PD,node(V)": ("fF", "the PD node at reverse bias V: the junction plus the EC and TG diffusions and "
                           "their gate overlaps (what a SPICE discharge of the PD sees)",
                     "what the pixel's PD node holds: the diffusions add 1.5 fF to the junction"),
    "CG_jdep(V)": ("uV/e-", "q / C_jdep(V): the PD-referred conversion gain of the junction alone at bias V "
                            "(table 3.2 of [Thesis2019] gives it at 2.5 V)",
                   "the thesis's table 3.2 figure, kept to compare with it"),
    "CG_PD,node(V)": ("uV/e-", "q / C_PD,node(V): the PD-referred conversion gain of the PD node at bias V; "
                               "verify's pd_conversion_gain_<kind> measures it in SPICE (the PD node's drop per "
                               "collected electron at a small signal from the PD reset level)",
                      "the gain the pixel's PD really has; CG_jdep leaves the EC / TG diffusions out (20 % on "
                      "the secondary)"),
    "CG_out(0)": ("uV/e-", "output-referred conversion gain at zero signal: A_sf q / (C_PD,node + C_FD) at the "
                           "PD reset level (the charge shares PD node and FD after the transfer; A_sf from the SF's "
                           "SPICE operating point)",
                  "what a small signal gives at the column; verify's conversion_gain_<kind> is its SPICE value"),
    "CG_out(0-30 %)": ("uV/e-", "mean slope of the double-sampled SPICE column signal against the collected "
                                "charge over 0 - 30 % of the column swing (the simulation experiment's sweep): "
                                "below CG_out(0) as C(V) grows while the node discharges",
                       "the slope of the signals the sizing uses, not only their start"),
    "K x LSB": ("uV/e-", "the EMVA 1288 system gain K (photon-transfer slope over 0 - 70 % of saturation) as a "
                         "voltage per electron: below CG_out(0) for the same C(V) reason",
                "EMVA 1288's gain, what a camera measurement reports"),
    "FW_jdep(V)": ("ke-", "pixel swing x C_jdep(V) / q: the full well of [Thesis2019] table 3.2 (the junction "
                          "alone, its capacitance held at bias V)",
                   "the thesis's table, kept to compare with it"),
    "FW_jdep,CV(V)": ("ke-", "the charge the junction alone gives up from bias V down by the pixel swing, its "
                             "C(V) integrated",
                      "FW_jdep without the fixed capacitance: C grows as the PD discharges"),
    "full well at the column": ("e-", "column swing (saturated minus dark double-sampled SPICE signal) over "
                                      "CG_out(0) in SPICE: the charge, referred through the small-signal gain, at "
                                      "which the column output saturates; verify's full_well_<kind> (a sign-off "
                                      "row shows it at the spec's worst condition, the nominal one beside it)",
                                "what the readout lets through: the column clips (the follower's V_GS and the "
                                "column's ground) before the PD reaches the bottom of the pixel swing, so it is "
                                "below FW_jdep"),
    "mu_e.sat (EMVA)": ("e-", "EMVA 1288 saturation capacity of the virtual camera: the mean signal at the "
                              "photon-transfer variance maximum, divided by K",
                        "EMVA 1288's definition, from an exposure series: the variance peaks before the column "
                        "clips, so it is below the full well at the column"),
    "read noise at the column": ("e-", "temporal noise of the pixel chain at the column with non-correlated "
                                       "double sampling (kT/C of the resets and the TG partition, the SF and its "
                                       "load, the dark shot noise of t_int), divided by CG_out(0)",
                                 "the pixel's own noise, before the AFE"),
    "read noise with the AFE": ("e-", "read noise at the column plus the SC AFE's kT/C and op-amp noise "
                                      "(referred to its input), divided by CG_out(0); verify's read_noise_<kind>",
                                "what the chip's output carries"),
    "sigma_d (EMVA)": ("e-", "EMVA 1288 dark temporal noise: the dark images' temporal noise (quantization "
                             "removed) divided by K: the read noise at the column referred through K instead of "
                             "CG_out(0), plus the dark shot noise",
                       "EMVA 1288's figure, what a camera measurement reports"),
    "pedestal": ("mV", "double-sampled output at zero light: switch charge injection and feedthrough and the "
                       "PD / FD reset offsets, not dark current (which adds a few electrons in the window)",
                 "an offset, not a dark signal: named so it is not read as one"),
    "DSNU, model": ("mV", "dark-signal non-uniformity of the virtual camera: the TG channel charge's mismatch "
                          "only (half of it lands on FD), at the column",
                    "the camera model's one mismatch source"),
    "DSNU, Monte Carlo": ("mV", "pixel-to-pixel sigma of the dark frame after double sampling, every device "
                                "drawn from the GF180 statistical models (one chip, SPICE)",
                          "every device's mismatch, in SPICE"),
}

#: The names whose value depends on a bias (written with "(V)"), the bias filled in by ``_at``.
BIASED = tuple(n[:-3] for n in GLOSSARY if n.endswith("(V)"))


def _at(name: str, v: float) -> str:
    return name.replace("(V)", f"({v:g} V)")


def c_jdep(v: float) -> str:
    return _at("C_jdep(V)", v)


def c_node(v: float) -> str:
    return _at("C_PD,node(V)", v)


def cg_jdep(v: float) -> str:
    return _at("CG_jdep(V)", v)


def cg_node(v: float) -> str:
    return _at("CG_PD,node(V)", v)


def fw_jdep(v: float) -> str:
    return _at("FW_jdep(V)", v)


def fw_jdep_cv(v: float) -> str:
    return _at("FW_jdep,CV(V)", v)


def _generic(name: str) -> str:
    for stem in BIASED:
        if name.startswith(stem + "(") and name.endswith(" V)"):
            return stem + "(V)"
    return name


def unit_of(name: str) -> str:
    return GLOSSARY[_generic(name)][0]


def label(name: str) -> str:
    """``name (unit)``: the row label or column header of the figure ``name`` in a table."""
    return f"{name} ({unit_of(name)})"


#: The glossary table's columns.
GLOSSARY_COLUMNS = ["name", "unit", "definition", "why a name of its own"]


def glossary_rows(names) -> list[list[str]]:
    """[name, unit, definition, why] of each of ``names`` (in order), for the report's glossary table."""
    return [[n, unit_of(n), *GLOSSARY[_generic(n)][1:]] for n in names]
