"""The light map: every junction the top-metal shield leaves open, its node and area, its
photocurrent at the scene's irradiance, and the output error that current causes through the
real readout (SPICE).

From the drawn dual pixel with its column circuits (``DUALPIX_COL``) and the AFEs (``AFE_P``,
``AFE_S``, drawn in a chip), nets matched to the netlist (``nets.py``): a junction is a diffusion or a well of a net (N+ in the substrate, P+ in an
n-well, an n-well in the substrate); it is exposed where no metal (metal1 - metal5, the shield
included) covers it. ``shield``:

- ``pixels``: the shield as drawn today - over each subpixel but its light opening, the column
  circuits left open ([Thesis2019]'s chip: light reached its readout);
- ``full``: a top metal over everything but the pixels' light openings (the photodiodes' wells
  where the pixel's own shield leaves them open): only the photodiodes see light.

Each exposed junction's photocurrent (the technology's QE over the scene's spectrum, at the
scene's headlight irradiance on the die) is put on its node in the dual-pixel bench with its AFE
columns - an N+ junction draws it from its node to the substrate, a P+ junction in a well pushes it
from the well's supply into its node - and the AFE outputs are compared with the same bench
without it: the output error the light causes, per node and all together, against the read noise. The
light is switched on from the dark state at the frame's start and stays on through the design's own
exposures and the row's read (``output_errors``: not as constant sources, whose operating point would
start the floating readout nodes at their junctions' clamp).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .nets import AFE_NODES, GROUND

SIGNAL_AFE = ("in", "vm", "x", "c")     # AFE nodes where a photocurrent leaves charge (out is driven)

METALS = ("metal1", "metal2", "metal3", "metal4", "metal5")
KINDS = {"nsd": "N+ diffusion", "psd": "P+ diffusion in an n-well", "well": "n-well", "pd_n": "photodiode well",
         "ntap": "n-well tap", "ptap": "substrate tap"}
#: nets whose photocurrent flows into a source (supplies, clocks, the substrate): no output error
_DRIVEN = ("vdd", "vss", "vpdr", "vrst", GROUND)


@dataclass(frozen=True)
class Junction:
    net: str
    kind: str          # a key of KINDS
    area_m2: float
    current_A: float = 0.0


def exposed(geo, shield: str = "pixels") -> list[Junction]:
    """The junctions of ``geo`` no metal covers (``shield``: ``pixels`` as drawn, ``full`` the light
    openings only)."""
    import klayout.db as kdb
    if shield not in ("pixels", "full"):
        raise ValueError(shield)
    metal = kdb.Region()
    for m in METALS:
        for reg in geo.wires.get(m, {}).values():
            metal += reg
    if getattr(geo, "cover", None) is not None:    # the chip's metal over the cell (its shield strips)
        metal += geo.cover
    metal.merge()
    light = kdb.Region()
    for reg in geo.junctions.get("pd_n", {}).values():
        light += reg
    out = []
    d2 = geo.dbu ** 2
    for kind, nets in geo.junctions.items():
        for net, reg in nets.items():
            open_ = reg - metal
            if shield == "full":
                open_ = open_ & light
            a = open_.area() * d2
            if a > 0:
                out.append(Junction(net, kind, a))
    return sorted(out, key=lambda j: (-j.area_m2, j.net))


def irradiance(design) -> tuple[float, object]:
    """The scene's headlight irradiance on the die (W/m2) and its spectrum."""
    from ...physics.photo import Spectrum
    sc = design.scene
    if sc is None:
        from ...errors import ConfigError
        raise ConfigError(design.source, "scene", None, "a [scene] table (the light map needs its irradiance)")
    return sc.headlight, Spectrum.blackbody(sc.spectrum_temperature)


def with_currents(design, junctions) -> list[Junction]:
    from ...physics.photo import photocurrent
    e, spec = irradiance(design)
    return [Junction(j.net, j.kind, j.area_m2, photocurrent(e, j.area_m2, spec, design.tech.qe)) for j in junctions]


#: the collection model of the readout cells: their lateral grid and wavelength step (their currents are
#: sums over the scene's spectrum; the cells are up to 365 um long)
READOUT_GRID, READOUT_STEP = 0.5e-6, 100e-9


def _mapped(cell: str, net: str, n_secondary: int) -> bool:
    if cell == "DUALPIX_COL":
        return bench_node(net, n_secondary) is not None
    return net in AFE_NODES and net not in ("vdd", "vref")


def modelled(design, geo, cell: str, shield: str = "pixels", resolution: tuple | None = None) -> list[Junction]:
    """The junctions of ``cell`` that the light map puts on the bench, with the collection model's currents
    (``light.model = "modelled"``, docs/light-collection.md): every diffusion of those nets collects, not
    only where no metal covers it - the carriers the light generates anywhere in the cell (and, in the
    dual pixel's column cell, under its photodiodes' openings) diffuse to them. The cell repeats along the
    row (periodic x), ends at its top and bottom (reflecting); ``shield``: ``pixels`` the metals as drawn,
    ``full`` a top metal over all but the photodiodes' openings. Each junction's ``area_m2`` is its exposed
    area (as the geometric map gives it). ``resolution``: (lateral grid, wavelength step) instead of
    ``READOUT_GRID``, ``READOUT_STEP`` (a coarser model of the same cells: the tests')."""
    from .collection import polar, response
    e, spec = irradiance(design)
    n = design.secondary_per_pixel
    own = {polar(k, net) for k, nets in geo.junctions.items() if k in ("nsd", "psd") for net in nets
           if _mapped(cell, net, n)}
    r = response(design, geo, light="all" if shield == "pixels" else "full", own=own, periodic=(True, False),
                 grid=(resolution or (READOUT_GRID,))[0], step=(resolution or (None, READOUT_STEP))[1])
    seen = {(j.net, "psd" if j.kind == "psd" else "nsd"): j.area_m2 for j in exposed(geo, shield)}
    from ...physics.photo import responsivity
    out = []
    for name in sorted(own):
        net, kind = (name[:-3], "psd") if name.endswith(":p+") else (name, "nsd")
        rr = responsivity(r.wavelength_m, r.eta[name])
        current = e * r.cell_area_m2 * spec.mean(lambda w: np.interp(w, r.wavelength_m, rr, left=0.0, right=0.0))
        out.append(Junction(net, kind, seen.get((net, kind), 0.0), float(current)))
    return out


def bench_node(net: str, n_secondary: int) -> str | None:
    """The dual-pixel bench's node of a ``DUALPIX_COL`` net (None: inside a pixel or a driven line)."""
    if net in _DRIVEN or net.startswith("pix.") or net[:2] in ("ec", "tg") or net[:3] in ("rst", "rs_") \
            or net.startswith(("s1", "s2")):
        return None
    if net.startswith("out_"):
        return f"in_col_{net[4:]}"
    if net.startswith("nbias"):
        return "nbias"
    if net == "col_p" or (net.startswith("col_s") and int(net[5:]) < n_secondary):
        return net
    return None


def sources(junctions, n_secondary: int) -> list:
    """Current sources of the junctions' photocurrents on the bench's nodes."""
    from ...spice.netlist import Element
    out = []
    for k, j in enumerate(junctions):
        node = bench_node(j.net, n_secondary)
        if node is None or j.current_A <= 0:
            continue
        pins = ("vdd", node) if j.kind == "psd" else (node, "0")
        out.append(Element(f"Ilight{k}", pins, j.current_A))
    return out


def afe_sources(afe_junctions) -> list:
    """Current sources inside the SC stage (``scafe``, one for every column: the mean of the drawn
    AFE_P's and AFE_S's exposed junctions) on the nodes it has; the op-amp's inner nodes are left out."""
    from ...spice.netlist import Element
    acc = {}
    for js in afe_junctions:
        for j in js:
            if j.net in AFE_NODES and j.net not in ("vdd", "vref") and j.current_A > 0:
                pins = ("vdd", j.net) if j.kind == "psd" else (j.net, "0")
                acc[pins] = acc.get(pins, 0.0) + j.current_A / len(afe_junctions)
    return [Element(f"Ilight{k}", pins, i) for k, (pins, i) in enumerate(sorted(acc.items()))]


#: the light map's windows: ``exposure`` (its figure), ``row``, ``steady`` (``output_errors``)
WINDOWS = ("exposure", "row", "steady")
#: the benches' tolerances: the light's effect through a clocked readout is microvolts, and at the engine's
#: default tolerances the difference of two benches (lit minus dark) scatters by up to a millivolt on the long
#: benches (the figure at 0.5 / 1 / 2 / 10 x the light: -0.20 / +0.40 / +0.69 / +0.05 mV on col_p); at these
#: (the converged tolerances of ``chip.frame``) by about 10 uV (docs/post-layout.md)
CONVERGED = (("reltol", 1e-6), ("abstol", 1e-12))


def output_errors(design, junctions, backend: str = "batch", afe_junctions=(), windows=("exposure", "row")) -> dict:
    """AFE output of each column with the junctions' photocurrents minus without (V), by SPICE, for each of
    ``windows`` ({window: {column: V}}; ``afe_junctions``: the drawn AFEs' exposed junctions, one list per
    AFE cell):

    - ``exposure`` (the light map's figure): the light switched on from the dark state at the frame's
      start and on through the design's own integration times (``primary.t_int``, ``secondary.t_int``:
      each array read after its real exposure, the readout idle meanwhile) and the first row's read;
    - ``row``: lit from the first row's start only (what a readout clocked through the exposure keeps), on
      the bench of the experiment's window (both arrays' rows at once, as the one AFE cell serves both);
    - ``steady``: the light on as constant sources for the whole bench of the experiment's window: the
      operating point at t = 0 is then the lit circuit's equilibrium, the floating readout nodes at their
      junctions' clamp, a state the clocked readout does not reach within a frame (docs/post-layout.md);
      kept as the virtual chip of ``gap``'s ``readout_light_idle``.
    """
    from dataclasses import replace as _r
    from ...circuits.testbench import dual_pixel_bench, real_timings, timings
    from ...gap.circuit_edits import EDGE, pulse
    from ...measure.afe import afe_output
    from ...spice import simulate_many
    bad = [w for w in windows if w not in WINDOWS]
    if bad:
        raise ValueError(f"light map window {bad[0]!r}: one of {', '.join(WINDOWS)}")
    n = design.secondary_per_pixel
    real, short = real_timings(design), timings(design, design.experiment.t_window)
    benches = {"exposure": real, "row": short, "steady": short}
    decks, keys = [], []
    for name, tm in (("real", real), ("window", short)):
        used = [w for w in windows if benches[w] is tm]
        if not used:
            continue
        decks.append(dual_pixel_bench(design, 0.0, 0.0, with_afe=True, title=f"light_dark_{name}", tm=tm))
        keys.append((None, tm))
        t1 = max(t.t_stop for t in tm.values()) - EDGE
        for w in used:
            start = {"exposure": EDGE, "row": min(t.row(0) for t in tm.values())}.get(w)

            def timed(els, start=start):
                return list(els) if start is None else [_r(e, value=pulse(start, t1, e.value)) for e in els]
            lit = dual_pixel_bench(design, 0.0, 0.0, with_afe=True, title=f"light_readout_{w}", tm=tm)
            inner = timed(afe_sources(afe_junctions))
            subs = tuple(_r(sc, elements=sc.elements + tuple(inner)) if sc.name == "scafe" else sc for sc in lit.subckts)
            decks.append(_r(lit, elements=(*lit.elements, *timed(sources(junctions, n))), subckts=subs))
            keys.append((w, tm))
    results = simulate_many(decks, backend=backend, options=CONVERGED)
    out, dark = {}, None
    for (w, tm), r in zip(keys, results):
        if w is None:
            dark = r
            continue
        out[w] = {}
        for col in ["col_p", *(f"col_s{k}" for k in range(n))]:
            t = tm["primary" if col == "col_p" else "secondary"]
            out[w][col] = afe_output(r, t, 0, f"out_{col}") - afe_output(dark, t, 0, f"out_{col}")
    return out


def output_error(design, junctions, backend: str = "batch", afe_junctions=(), window: str = "exposure") -> dict:
    """``output_errors`` of one ``window`` ({column: V})."""
    return output_errors(design, junctions, backend, afe_junctions, (window,))[window]


def read_noise_at_afe(design) -> dict:
    """Read noise (V rms) at each array's AFE output: the column's NCDS read noise (``physics.noise``)
    through the AFE's gain C11 / C13."""
    from ...camera.spicenoise import sf_gain
    from ...physics.noise import chain
    from ...techfit.ekv import models_for
    a = sf_gain(design)
    g = design.afe.c11 / design.afe.c13
    m = models_for(design)
    return {w: chain(design, w, a, m)["pixel_V"] * g for w in ("primary", "secondary")}


LIGHTS = ("geometric", "modelled")


def light_map(design, shield: str = "pixels", backend: str = "batch", geos: dict | None = None,
              light: str | None = None, resolution: tuple | None = None) -> dict:
    """The light map of ``design`` under ``shield``: exposed junctions (node, kind, area, photocurrent) of
    the dual pixel with its column circuits and of the AFEs, the AFE output error of each column by
    SPICE, its ratio to the read noise there. ``geos``: ``chip_geometry(design)`` when already made;
    ``light``: ``geometric`` (exposed area x QE) or ``modelled`` (the collection model of each readout
    cell, ``resolution`` as :func:`modelled`) instead of the design's ``light.model``."""
    from . import chip_geometry
    light = light or design.light.model
    if light not in LIGHTS:
        raise ValueError(f"light {light!r}: one of {', '.join(LIGHTS)}")
    geos = geos if geos is not None else chip_geometry(design, ("DUALPIX_COL", "AFE_P", "AFE_S"))
    if light == "modelled":
        js = modelled(design, geos["DUALPIX_COL"], "DUALPIX_COL", shield, resolution)
        afe = {c: modelled(design, geos[c], c, shield, resolution) for c in ("AFE_P", "AFE_S")}
    else:
        js = with_currents(design, exposed(geos["DUALPIX_COL"], shield))
        afe = {c: with_currents(design, exposed(geos[c], shield)) for c in ("AFE_P", "AFE_S")}
    errs = output_errors(design, js, backend, list(afe.values()))
    err, err_row = errs["exposure"], errs["row"]
    noise = read_noise_at_afe(design)
    e, _ = irradiance(design)
    rows = [{"cell": "DUALPIX_COL", "net": j.net, "node": bench_node(j.net, design.secondary_per_pixel) or "-",
             "kind": KINDS[j.kind], "area_m2": j.area_m2, "current_A": j.current_A,
             "readout": j.net.startswith(("col", "out", "nbias"))} for j in js]
    for cell, lst in afe.items():
        rows += [{"cell": cell, "net": j.net, "node": f"scafe.{j.net}" if j.net in _AFE_SIMULATED else "-",
                  "kind": KINDS[j.kind], "area_m2": j.area_m2, "current_A": j.current_A, "readout": True}
                 for j in lst]
    cols = {c: {"error_V": v, "read_noise_V": noise["primary" if c == "col_p" else "secondary"],
                "error_over_noise": abs(v) / noise["primary" if c == "col_p" else "secondary"],
                "error_from_row_V": err_row[c],
                "error_from_row_over_noise": abs(err_row[c]) / noise["primary" if c == "col_p" else "secondary"]}
            for c, v in err.items()}
    return {"shield": shield, "light": light, "irradiance_W_m2": e, "junctions": rows, "columns": cols,
            "readout_area_m2": sum(r["area_m2"] for r in rows if r["readout"]),
            "afe_area_m2": {c: sum(j.area_m2 for j in lst) for c, lst in afe.items()},
            "worst_error_over_noise": max(c["error_over_noise"] for c in cols.values())}


_AFE_SIMULATED = ("in", "out", "vm", "x", "c", "p1", "p1b", "p2", "p2b")


def open_readout(col_geo, afe_geos, n_secondary: int, shield: str = "pixels") -> tuple:
    """(bench node, kind, m2) of every junction ``shield`` leaves open on the readout's signal nodes: each
    column's sampling node (``in_<col>``) and line (``<col>``) from ``DUALPIX_COL``, and the AFE's ``in``,
    ``vm``, ``x``, ``c`` (``scafe.<node>``: the mean of the drawn AFEs, as one ``scafe`` serves every column)."""
    out = [(bench_node(j.net, n_secondary), j.kind, j.area_m2) for j in exposed(col_geo, shield)
           if j.net.startswith(("out_", "col_"))]
    out = [o for o in out if o[0] is not None]
    afe = {}
    for g in afe_geos:
        for j in exposed(g, shield):
            if j.net in SIGNAL_AFE:
                k = (f"scafe.{j.net}", j.kind)
                afe[k] = afe.get(k, 0.0) + j.area_m2 / len(afe_geos)
    return tuple(out + [(node, kind, a) for (node, kind), a in sorted(afe.items())])
