"""Benches whose identical copies are simulated once (issue 41: fewer sign-off decks, same figures)."""
from __future__ import annotations

from dataclasses import replace


def one_column(design, draw=None):
    """The design whose dual pixel has one secondary column, when its N secondary columns are copies of
    each other: the schematic (no extracted parasitics, which differ line to line) with nominal devices
    (no Monte Carlo draw). Each column of an array bench has its own bias generator and shares only
    ideal supplies and row lines with the others (``circuits.array``), so column 0 simulates as it does
    beside its copies and a bench of the copies costs N times one column (settling, power). Else None."""
    if draw is not None or getattr(design, "post_layout", None) is not None or design.secondary_per_pixel == 1:
        return None
    return replace(design, secondary_per_pixel=1)
