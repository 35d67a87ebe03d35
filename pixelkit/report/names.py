"""One name per figure in the report: the figures that exist in more than one definition.

A conversion gain, a read noise or a DSNU can be defined several ways (which capacitance,
at which bias, referred through which gain, which effects included); the report gives each
definition its own name, uses that name wherever the figure appears (``label``), and the
summary section lists them with their definitions (``glossary_rows``).
``tests/test_report_names.py`` checks that a name never carries two values in one report.
"""
from __future__ import annotations

#: name -> (unit as printed, definition). Bias-dependent names are made by ``cg_jdep`` / ``c_jdep``.
GLOSSARY = {
    "C_jdep(V)": ("fF", "capacitance of the PD junction alone (area and perimeter terms) at reverse bias V"),
    "C_PD,node(V)": ("fF", "the PD node at reverse bias V: the junction plus the EC and TG diffusions and "
                           "their gate overlaps (what a SPICE discharge of the PD sees)"),
    "CG_jdep(V)": ("uV/e-", "q / C_jdep(V): the PD-referred conversion gain of the junction alone at bias V "
                            "(table 3.2 of [Thesis2019] gives it at 2.5 V)"),
    "CG_out(0)": ("uV/e-", "output-referred conversion gain at zero signal: A_sf q / (C_PD,node + C_FD) at the "
                           "PD reset level (the charge shares PD node and FD after the transfer; A_sf from the SF's "
                           "SPICE operating point)"),
    "CG_out(0-30 %)": ("uV/e-", "mean slope of the double-sampled SPICE column signal against the collected "
                                "charge over 0 - 30 % of the column swing (the simulation experiment's sweep): "
                                "below CG_out(0) as C(V) grows while the node discharges"),
    "K x LSB": ("uV/e-", "the EMVA 1288 system gain K (photon-transfer slope over 0 - 70 % of saturation) as a "
                         "voltage per electron: below CG_out(0) for the same C(V) reason"),
    "read noise at the column": ("e-", "temporal noise of the pixel chain at the column with non-correlated "
                                       "double sampling (kT/C of the resets and the TG partition, the SF and its "
                                       "load, the dark shot noise of t_int), divided by CG_out(0)"),
    "read noise with the AFE": ("e-", "read noise at the column plus the SC AFE's kT/C and op-amp noise "
                                      "(referred to its input), divided by CG_out(0)"),
    "sigma_d (EMVA)": ("e-", "EMVA 1288 dark temporal noise: the dark images' temporal noise (quantization "
                             "removed) divided by K: the read noise at the column referred through K instead of "
                             "CG_out(0), plus the dark shot noise"),
    "pedestal": ("mV", "double-sampled output at zero light: switch charge injection and feedthrough and the "
                       "PD / FD reset offsets, not dark current (which adds a few electrons in the window)"),
    "DSNU, model": ("mV", "dark-signal non-uniformity of the virtual camera: the TG channel charge's mismatch "
                          "only (half of it lands on FD), at the column"),
    "DSNU, Monte Carlo": ("mV", "pixel-to-pixel sigma of the dark frame after double sampling, every device "
                                "drawn from the GF180 statistical models (one chip, SPICE)"),
}


def _at(name: str, v: float) -> str:
    return name.replace("(V)", f"({v:g} V)")


def c_jdep(v: float) -> str:
    return _at("C_jdep(V)", v)


def c_node(v: float) -> str:
    return _at("C_PD,node(V)", v)


def cg_jdep(v: float) -> str:
    return _at("CG_jdep(V)", v)


def _generic(name: str) -> str:
    if name.startswith(("C_jdep(", "C_PD,node(", "CG_jdep(")) and name.endswith(" V)"):
        return name[:name.index("(")] + "(V)"
    return name


def unit_of(name: str) -> str:
    return GLOSSARY[_generic(name)][0]


def label(name: str) -> str:
    """``name (unit)``: the row label or column header of the figure ``name`` in a table."""
    return f"{name} ({unit_of(name)})"


def glossary_rows(names) -> list[list[str]]:
    """[name, unit, definition] of each of ``names`` (in order), for the report's glossary table."""
    return [[n, unit_of(n), GLOSSARY[_generic(n)][1]] for n in names]
