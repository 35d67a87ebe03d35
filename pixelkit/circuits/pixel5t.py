"""The 5T global-shutter pixel ([Thesis2019] fig. 3.2) as a subcircuit.

Ports: ``vdd`` (SF drain), ``vpdr`` (EC drain: the PD reset level, which the
thesis made adjustable from outside), ``vrst`` (RST drain: the FD reset level),
``ec``, ``tg``, ``rst``, ``rs`` (gates), ``col`` (column line). Parameter ``iph``:
the photocurrent (A) of the PD.

    EC:  vpdr -> pd   resets the photodiode (exposure starts when EC opens)
    TG:  pd -> fd     transfers (shares) the charge to the storage node FD
    RST: vrst -> fd   resets FD

With gates at the supply, reset levels below VDD - Vth(body) make both resets
*hard* (the switch stays in its linear region): no soft-reset lag, and the TG
conducts as soon as it opens, so even a small signal is shared onto FD.
    SF:  vdd, gate fd, source sfo
    RS:  sfo -> col   row select

FD is a storage node with its own light and leakage: ``Fpls`` draws 1/gse of the
photocurrent from it (``physics.fd.gse``: the design's ``pixel.gse``, or the collection model's); it leaks through the
TG and RST diffusions by the device models' junction law (``physics.fd.leakage``).
"""
from __future__ import annotations

from ..spice.netlist import Element, Param, Subckt
from ..physics.fd import gse
from .devices import mosfet, photodiode

PORTS = ("vdd", "vpdr", "vrst", "ec", "tg", "rst", "rs", "col")


def pixel5t(design, which: str, compressed: bool = False) -> Subckt:
    """The 5T subpixel of ``which`` ("primary" or "secondary") of ``design``.

    ``compressed`` (frames that simulate a long ``t_int`` over a short window): the light is
    ``iph_read`` (A, what the pixel really sees) plus ``iph_exp`` while the port ``expo`` is at
    1 V (the exposure: the charge of ``t_int`` in the window), so the storage node and a PD
    not held in reset see the real light while the rows wait, not the compressed one
    (subckt ``pix5t_<which>_c``, port ``expo`` last)."""
    sub = getattr(design, which)
    dev = design.pixel.devices
    t = design.tech
    light = (Element("Iph", ("pd", "nph"), Param("iph")),) if not compressed else (
        Element("Iph", ("pd", "nph"), Param("iph_read")),
        Element("Gexp", ("pd", "nph", "expo", "0"), Param("iph_exp")))
    return Subckt(f"pix5t_{which}{'_c' if compressed else ''}", PORTS + (("expo",) if compressed else ()), (
        photodiode("pd", "pd", sub.area, sub.perimeter, t),
        *light,
        Element("Vph", ("nph", "0"), 0.0),             # senses the photocurrent for Fpls
        # storage node: parasitic light, 1/gse of the PD's photocurrent (its leakage is the
        # BSIM4 junction current of the TG and RST diffusions, in the device models)
        Element("Fpls", ("fd", "0", "Vph"), 1.0 / gse(design, which)),
        mosfet("ec", "vpdr", "ec", "pd", "0", dev.ec_w, dev.ec_l, t),
        mosfet("tg", "fd", "tg", "pd", "0", dev.tg_w, dev.tg_l, t),
        mosfet("rst", "vrst", "rst", "fd", "0", dev.rst_w, dev.rst_l, t),
        mosfet("sf", "vdd", "fd", "sfo", "0", dev.sf_w, dev.sf_l, t),
        mosfet("rs", "sfo", "rs", "col", "0", dev.rs_w, dev.rs_l, t),
        *wiring(design, f"pix5t_{which}"),
    ), (("iph_read", 0.0), ("iph_exp", 0.0)) if compressed else (("iph", 0.0),))


def wiring(design, cell: str) -> tuple:
    """The extracted wiring capacitances of subcircuit ``cell`` (post-layout view; none on the schematic)."""
    pl = design.post_layout
    if pl is None:
        return ()
    if cell == "scafe":
        pl.require_afe("the AFE's wiring (scafe)")
    return tuple(Element(f"Cw{k}", (a, b), c) for k, (a, b, c) in enumerate(pl.cells.get(cell, ())))
