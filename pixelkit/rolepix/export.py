"""The decks of a pixel read by role that run alone: what ``pixelkit netlist --bench NAME`` writes
for a ``pixel4t`` or ``netlist`` design (each also runs as it is in ``ngspice -b``)."""
from __future__ import annotations

from .signal import LADDER, current_for, flush_exposure


#: the ``cds`` deck ``pixelkit netlist`` writes: electrons of each pixel in the window frame
CDS_EXPORT_E = (0.0, 1e3, 1e4)


def export_benches(design) -> dict:
    """The decks of a role design that run alone (``pixelkit netlist --bench NAME``), by name: ``cds`` (flush,
    window, window: a dark pixel and pixels of 1 ke- and 10 ke- in the window, then a dark frame),
    ``ladder`` (the ladder deck), ``dark`` (the dark-current deck), ``noise`` (the .noise deck at the
    read point: this one simulates the lag deck first), ``cell`` (the pixel's subcircuit alone)."""
    from dataclasses import replace
    from ..circuits.cds import cds_bench
    from ..spice.netlist import Netlist, Op

    def cds():
        ex = design.experiment
        tw, t0 = ex.t_window, flush_exposure(design)
        return cds_bench(design, design.cell(), [t0, tw, tw],
                         [[0.0, current_for(design, n, tw), 0.0] for n in CDS_EXPORT_E], title="role_cds")

    def lad():
        tw, t0 = design.experiment.t_window, flush_exposure(design)
        return cds_bench(design, design.cell(), [t0, tw],
                         [[0.0, 0.0]] + [[0.0, current_for(design, n, tw)] for n in LADDER], title="role_ladder")

    def dark():
        from .dark import OPTIONS
        t0 = flush_exposure(design)
        net = cds_bench(design, design.cell(), [t0, t0, max(design.array.t_int, 2 * t0)], [[0.0] * 3], title="role_dark")
        return replace(net, options=(*net.options, *OPTIONS))

    def noise():
        from .noise import deck, read_point
        return deck(design, read_point(design)["v_fd"])

    def cell():
        c = design.cell()
        t = design.tech
        return Netlist(title=c.subckt.name, elements=(), analysis=Op(), subckts=(*c.support, c.subckt),
                       models=c.models, includes=t.models.includes(design.corner or None))
    return {"cds": cds, "ladder": lad, "dark": dark, "noise": noise, "cell": cell}
