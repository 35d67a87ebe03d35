"""Running role decks: the engine, a Monte Carlo draw of the devices, and the record of what ran."""
from __future__ import annotations

from dataclasses import replace


def apply_draw(net, design, draw):
    """``net`` with the devices of Monte Carlo sample ``draw`` (``verify.mismatch``: the model library's
    own per-instance statistics, or the kit's Pelgrom draw); unchanged without one."""
    if draw is None:
        return net
    from ..verify import mismatch
    if draw.source == "library":
        from ..circuits.array import MISMATCH_INCLUDE
        return replace(net, includes=(*net.includes, MISMATCH_INCLUDE),
                       options=(*net.options, ("seed", draw.ngspice_seed)))
    return mismatch._pelgrom(net, design, draw)


def run(nets, design, draw=None, backend: str = "batch") -> list:
    """Simulate ``nets`` (each with the draw applied), in order; one worker (the verify task is already
    one worker of the grid). While ``verify.measure.recording`` is active the results are recorded."""
    from ..spice import simulate_many
    from ..verify.measure import record
    out = simulate_many([apply_draw(n, design, draw) for n in nets], backend=backend, jobs=1)
    record(out)
    return out
