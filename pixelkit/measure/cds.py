"""Readings of a true-CDS bench (``circuits.cds``): the held reset and signal samples of a frame."""
from __future__ import annotations


def hold_time(timing, exposures, starts, frame: int) -> float:
    """An instant when both of ``frame``'s samples are held (the end of its row read)."""
    return starts[frame] + timing.frame(exposures[frame]).t_hold


def samples(result, timing, exposures, starts, column: int, frame: int) -> tuple[float, float]:
    """(reset level, signal level) held on column ``column``'s SHR / SHS capacitors after ``frame``."""
    t = hold_time(timing, exposures, starts, frame)
    return float(result.at(f"v(vshr{column})", t)), float(result.at(f"v(vshs{column})", t))


def cds(result, timing, exposures, starts, column: int, frame: int) -> float:
    """The true-CDS output (V): reset sample minus signal sample of the same read."""
    r, s = samples(result, timing, exposures, starts, column, frame)
    return r - s
