"""The device parts of the pixel's capacitive nodes, and the photodiode node built from them.

A MOS source/drain on a node adds junction terms (bottom + field sidewall, gate-edge
sidewall, the technology's MOS junction parameters) and a gate overlap (``overlap``:
``cgso W`` plus BSIM4 capmod 2's bias-dependent LDD part). ``pd_node`` is the photodiode
with, optionally, the EC and TG source diffusions that hang on it in the pixel. Both the
FD (``fd``) and the subpixel figures (``subpixel``) are built on this module.
"""
from __future__ import annotations

import numpy as np

from .geometry import diffusion
from .junction import Junction, Node


def mos_junctions(tech) -> tuple[Junction, Junction]:
    """(bottom + field sidewall, gate-edge sidewall) junctions of the technology's MOS diffusions."""
    mos = tech.mos
    return (Junction(mos.cj, mos.mj, mos.pb, mos.cjsw, mos.mjsw, mos.pbsw),
            Junction(0.0, 0.5, 1.0, mos.cjswg, mos.mjswg, mos.pbswg))


def overlap(w: float, v_ov: float, mos) -> float:
    """Gate overlap capacitance (F) of width ``w`` at overlap voltage ``v_ov`` = V_gate - V_diffusion."""
    ldd = 1.0 if v_ov >= 0 else 1.0 - 1.0 / np.sqrt(1.0 - 4.0 * v_ov / mos.ckappa)
    return w * (mos.cgso + mos.cgsl * ldd)


def switch_side(w: float, tech, v_ov: float = 0.0) -> tuple[tuple, float]:
    """Junction terms and overlap C (F) one source/drain of width ``w`` adds to a node."""
    body, edge = mos_junctions(tech)
    a, p = diffusion(w, tech.mos.diff_ext)
    return ((a, p - w, body), (0.0, w, edge)), overlap(w, v_ov, tech.mos)


def pd_node(design, which: str, parasitics: bool = False) -> Node:
    """C(V) of the photodiode of ``which`` subpixel, optionally with its switch parasitics
    (EC and TG source diffusions and overlaps, gates at 0 V, overlaps at the PD reset level; post-layout,
    the extracted wiring on the PD node too)."""
    sub = getattr(design, which)
    tech = design.tech
    terms = [(sub.area, sub.perimeter, Junction.of(tech.photodiode))]
    c_fixed = 0.0
    if parasitics:
        dev = design.pixel.devices
        for w in (dev.ec_w, dev.tg_w):
            t, c = switch_side(w, tech, -design.pixel.v_pd_reset)
            terms += t
            c_fixed += c
        c_fixed += wiring(design, which, "pd")
    return Node(tuple(terms), c_fixed)


def wiring(design, which: str, node: str, a_sf: float | None = None) -> float:
    """Extracted wiring capacitance (F) on ``node`` of ``which`` subpixel: 0 on the schematic view,
    the layout's on the post-layout view (``design.post_layout``)."""
    pl = getattr(design, "post_layout", None)
    return 0.0 if pl is None else pl.node_wiring(which, node, a_sf)


def line_cap(design, col: str) -> float:
    """The column line's lumped capacitance: ``pixel.column_cap`` (schematic), or post-layout the
    extracted line of the other rows and the column circuit (``layout.pex.overlay``)."""
    pl = design.post_layout
    if pl is None:
        return design.pixel.column_cap
    return pl.column_cap["primary" if col.startswith("col_p") else "secondary"]
