"""Saturation time against mask opening ([Thesis2019] fig. 3.6).

A PD of fixed junction (its C does not depend on the opening) is discharged by
I = R(lambda) E A_open from the reset bias to zero bias. The thesis's linear
estimate is t_sat = V_R C_jdep(V_R) / I; with C(V) the time is
(Q(V_R) - Q(0)) / I, longer because C grows as the reverse bias falls. Both
scale exactly as 1 / A_open.
"""
from __future__ import annotations

import numpy as np

from .discharge import time_to, time_to_linear
from .photo import Spectrum, photocurrent


def saturation_times(node, v_reset: float, irradiance: float, spectrum: Spectrum, qe_of, openings):
    """(photocurrents A, t_sat linear s, t_sat with C(V) s) for each opening (m^2)."""
    openings = np.asarray(openings, dtype=float)
    currents = np.array([photocurrent(irradiance, a, spectrum, qe_of) for a in openings])
    c0 = float(node.capacitance(v_reset))
    lin = np.array([time_to_linear(c0, v_reset, i) for i in currents])
    cv = np.array([time_to(node, v_reset, 0.0, i) for i in currents])
    return currents, lin, cv
