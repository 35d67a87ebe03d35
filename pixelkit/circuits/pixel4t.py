"""The 4T pinned-photodiode pixel as a subcircuit (family ``pixel4t``).

    PPD --TG--> FD;  RST: vrst -> FD;  SF: vdd, gate FD, source sfo;  RS: sfo -> col

Ports ``vdd vrst rst tg rs col pklight``. The pinned photodiode and the transfer gate are the
behavioural model of ``circuits.ppd`` (the technology has no pinned implant; docs/pixel4t.md says
what one would need); the transfer gate's FD side is its n+ diffusion (``ppd.fd_junction``) and its
gate-to-FD overlap. RST, SF and RS are the technology's MOSFETs. FD is everything on it: the TG
drain and RST source junctions, both overlaps, the SF gate.
"""
from __future__ import annotations

from ..physics.nodes import overlap
from ..physics.ppd import Channel, Ppd, dark_scale, pinning_voltage
from ..spice.netlist import Element, Subckt
from .devices import mosfet
from .ppd import LIGHT_PORT, fd_junction, ppd_elements
from .roles import PixelCell

PORTS = ("vdd", "vrst", "rst", "tg", "rs", "col", LIGHT_PORT)
ROLES = (("vdd", "vdd"), ("vrst", "vrst"), ("rst", "rst"), ("tg", "tg"), ("rs", "rs"), ("col", "col"))
PROBES = (("fd", "fd"), ("pd", "q"))


def ppd_model(design, channel: Channel, temperature_K: float | None = None) -> Ppd:
    """The ``physics.ppd.Ppd`` of ``design``'s PPD at ``temperature_K`` (default the design's)."""
    p, px = design.ppd, design.pixel
    t = design.temperature if temperature_K is None else temperature_K
    area, perim = px.ppd_width * px.ppd_height, 2 * (px.ppd_width + px.ppd_height)
    return Ppd(v_pin=pinning_voltage(p.v_pin, p.v_bi, t, p.t_ref), c=p.c_area * area + p.c_perimeter * perim,
               i_dif=p.j_dif * area * dark_scale(t, p.t_ref, "diffusion"),
               i_gen=p.j_gen * area * dark_scale(t, p.t_ref, "generation"),
               barrier=p.barrier, channel=channel, temperature=t)


def tg_overlap(design) -> float:
    """The TG gate-to-FD overlap (F): BSIM4's at the gate-off bias against FD's reset-drain level, as a
    linear capacitor (the behavioural TG has no bias-dependent overlap)."""
    t = design.tech
    return overlap(design.devices.tg_w, -design.levels.v_rst_for(t.supply), t.mos)


def pixel4t(design, channel: Channel, name: str = "pix4t") -> PixelCell:
    """The 4T pixel of ``design`` (its TG channel: ``channel``, the technology's NMOS EKV fit at the
    TG's size) as a :class:`PixelCell`."""
    dev, t = design.devices, design.tech
    ppd = ppd_model(design, channel)
    fdj, cards = fd_junction(t, dev.tg_w, design.temperature)
    el = (*ppd_elements(ppd, q="q", fd="fd", tg="tg"),
          *fdj,
          Element("Ctgfd", ("tg", "fd"), tg_overlap(design)),
          mosfet("rst", "vrst", "rst", "fd", "0", dev.rst_w, dev.rst_l, t),
          mosfet("sf", "vdd", "fd", "sfo", "0", dev.sf_w, dev.sf_l, t),
          mosfet("rs", "sfo", "rs", "col", "0", dev.rs_w, dev.rs_l, t))
    pl = getattr(design, "post_layout", None)
    if pl is not None:   # the post-layout view: the drawn cell's wiring (layout.pixel4t.extracted)
        el += tuple(Element(f"Cpex{i}", (a, b), c) for i, (a, b, c) in enumerate(pl.couplings))
    x = "X" if t.mos.kind == "subckt" else "M"
    return PixelCell(Subckt(name, PORTS, el, models=cards), ROLES, PROBES, source="circuits.pixel4t",
                     noise=((f"{x}sf", "gate"), (f"{x}rs", "drain")))
