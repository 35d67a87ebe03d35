"""The 4T pixel drawn on GF180MCU (``pixelkit layout`` of a ``pixel4t`` design): the 5T subpixel's floor
plan (``layout.pixel``) without the EC transistor - the photodiode, TG - RST in the first strip
(``pd | TG | fd | RST | vrst``), SF - RS in the second, the row lines, the column track and the shield.

The photodiode is the stand-in GF180MCU allows: an n-well / p-substrate junction of the design's PPD
size under the foundry's photodiode marker (docs/pixel4t.md says what a pinned implant would need:
a shallow n storage well depleting at V_pin, a p+ pinning layer tied to the substrate and self-aligned
to the TG edge, a TG threshold implant). DRC and LVS judge that stand-in; the simulations use the
behavioural PPD. The cell's LVS netlist (``PIX4T.spice``) is the four NMOS of the design with the
stand-in's junction diode at its drawn area and perimeter.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

from .canvas import box
from .pixel import SubpixelPlan, subpixel
from .primitives import pad_side
from .techview import LayoutTech

CELL = "PIX4T"
#: what the drawn photodiode is (the layout's output says it)
STAND_IN = ("a stand-in: an n-well / p-substrate junction under the photodiode marker (GF180MCU has no pinned "
            "implant: a pinned photodiode needs an n storage well depleting at V_pin, a p+ pinning layer "
            "self-aligned to the TG edge and a TG threshold implant; the simulations use the behavioural PPD)")
#: the cell's pins (the row lines and column as the 5T subpixel names them, and the substrate)
PINS = ("vdd", "vrst", "rst", "tg", "rs", "col", "vss")


@dataclass(frozen=True)
class _Sub:
    """What ``layout.pixel`` reads of a subpixel, from the 4T design."""
    pitch: float
    pd_width: float
    pd_height: float
    mask_opening: None = None


def _view(design):
    """The 4T design as ``layout.pixel`` reads a dual pixel: ``pixel.devices``, ``primary``, ``tech``."""
    px = design.pixel
    return SimpleNamespace(pixel=SimpleNamespace(devices=design.devices), tech=design.tech,
                           primary=_Sub(px.pitch, px.ppd_width, px.ppd_height), name=design.name)


def plan(design, lt) -> SubpixelPlan:
    px = design.pixel
    e = lt.snap(design.tech.rules.pd_to_cell_edge * 1e9)
    p = lt.snap(px.pitch * 1e9)
    pd = box(e, e, e + lt.snap(px.ppd_width * 1e9), e + lt.snap(px.ppd_height * 1e9))
    s = lt.space("metal2")
    col_x = p - s // 2 - pad_side(lt, "metal2") // 2
    return SubpixelPlan("primary", p, pd, None, "metal2", col_x, strip1=("tg", "rst"))


def cell(design):
    """The 4T cell (a :class:`~pixelkit.layout.canvas.Canvas` named ``PIX4T``)."""
    lt = LayoutTech(design.tech)
    cv = subpixel(_view(design), lt, plan(design, lt))
    cv.name = CELL
    return cv


def lvs_spice(design, cv) -> str:
    """The cell's netlist for LVS: the four NMOS (the technology's device, W and L of the design) and the
    stand-in photodiode (the foundry's n-well / p-substrate diode at the drawn PD's area and perimeter)."""
    from .signoff.schematic import pd_device
    t, d = design.tech, design.devices
    px = design.pixel
    w, h = px.ppd_width * 1e6, px.ppd_height * 1e6
    dev = t.mos.nmos
    lines = [f"* {design.name}: the 4T cell for LVS (the pinned photodiode's stand-in: an n-well junction)",
             f".subckt {CELL} " + " ".join(PINS),
             f"Dpd vss pd {pd_device(t)} AREA={w * h:g}p PJ={2 * (w + h):g}u"]
    for name, a, g, b in (("tg", "pd", "tg", "fd"), ("rst", "fd", "rst", "vrst"), ("sf", "vdd", "fd", "sfo"),
                          ("rs", "sfo", "rs", "col")):
        lines.append(f"M{name} {a} {g} {b} vss {dev} W={getattr(d, f'{name}_w') * 1e6:g}u "
                     f"L={getattr(d, f'{name}_l') * 1e6:g}u")
    return "\n".join([*lines, f".ends {CELL}", ".end"]) + "\n"


def layout_pixel4t(design, out_dir: Path, drc: bool = False, lvs: bool = False, foundry_lvs: bool = False) -> dict:
    """``<design>.gds`` and ``PIX4T.spice`` in ``out_dir`` (the cell and its LVS netlist); with ``drc`` /
    ``lvs`` / ``foundry_lvs`` its sign-off by ``pixelkit signoff``'s code (``layout.anylayout``: the foundry DRC
    deck, the kit's LVS with the extraction and the light map, the foundry's LVS deck) in ``out_dir/signoff``.
    ``exit_status``: the sign-off's (0 when nothing was asked)."""
    import gdstk

    from ..fileio import write_atomic
    from .flow import write_gds
    cv = cell(design)
    lib = gdstk.Library(name=design.name, unit=1e-6, precision=1e-9)
    lib.add(cv.to_gdstk(design.tech, {}))
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    gds = write_gds(lib, out_dir / f"{design.name}.gds")
    spice = write_atomic(out_dir / f"{CELL}.spice", lvs_spice(design, cv))
    r = {"gds": str(gds), "spice": str(spice), "top": CELL, "pitch_um": design.pixel.pitch * 1e6,
         "ppd_um": [design.pixel.ppd_width * 1e6, design.pixel.ppd_height * 1e6], "photodiode": STAND_IN,
         "exit_status": 0}
    if drc or lvs or foundry_lvs:
        from .anylayout import signoff
        skip = (() if drc else ("drc",)) + (() if lvs else ("lvs", "pex")) + (() if foundry_lvs else ("foundry-lvs",))
        r["signoff"] = signoff(gds, spice, design.tech, out_dir / "signoff", CELL, skip)
        r["exit_status"] = r["signoff"]["exit_status"]
    return r


@dataclass(frozen=True)
class Extracted:
    """The 4T cell's wiring capacitances as the simulated subcircuit ``pix4t`` names its nodes (F):
    ``couplings`` ((node, node, C), ...) among ``fd``, ``sfo``, its ports and ground (``0``); ``fd_F`` FD's
    total; ``dropped``: the stand-in photodiode's own wiring (its N+ contact and metal, which a pinned
    photodiode has not: a coupling of FD to it is kept, to ground)."""
    couplings: tuple
    fd_F: float
    dropped_F: float
    source: str


#: the drawn cell's nets -> the simulated subcircuit's nodes (the substrate and the shield are its ground)
NODE = {"fd": "fd", "sfo": "sfo", "vdd": "vdd", "vrst": "vrst", "rst": "rst", "tg": "tg", "rs": "rs", "col": "col",
        "vss": "0", "0": "0", "pd": "pd"}


def geometry(design):
    """The drawn 4T cell's ``pex.nets.NetGeometry``, its nets named by its LVS netlist."""
    import tempfile

    from .pex.nets import view_geometry
    from .signoff.netlist_in import read_netlist
    from ..tech.stack import require_stack
    require_stack(design.tech)
    with tempfile.TemporaryDirectory(prefix="pixelkit-4t-") as tmp:
        r = layout_pixel4t(design, Path(tmp))
        view = read_netlist(r["spice"], design.tech).top_view(CELL)
        return view_geometry(r["gds"], CELL, design.tech, view)


def extracted(design) -> Extracted:
    """The drawn cell's couplings placed in ``pix4t`` (``Extracted``'s docstring says where each goes)."""
    from .pex.capacitance import capacitances
    cpl = capacitances(geometry(design), design.tech.stack)
    acc, dropped = {}, 0.0
    for (a, b), c in cpl.items():
        a, b = NODE.get(a, "0"), NODE.get(b, "0")
        if "pd" in (a, b):
            other = b if a == "pd" else a
            if other in ("0", "pd"):
                dropped += c
                continue
            a, b = other, "0"
        if a == b or c <= 1e-19:
            continue
        key = tuple(sorted((a, b)))
        acc[key] = acc.get(key, 0.0) + c
    pairs = tuple((a, b, c) for (a, b), c in sorted(acc.items()))
    fd = sum(c for a, b, c in pairs if "fd" in (a, b))
    return Extracted(pairs, fd, dropped, f"extracted from the drawn {CELL} of {design.name} ({design.tech.stack.source})")


def post_layout_view(design):
    """``design`` carrying its drawn cell's extraction: its generator then adds the couplings to ``pix4t``."""
    from dataclasses import replace
    return replace(design, post_layout=extracted(design))
