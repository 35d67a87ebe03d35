"""Virtual silicon of the chip with its readout open to light: the gap diagnosis's check on the light map.

The thesis's chip [Thesis2019] failed because light reached junctions of its AFE and output stage. This module
makes the lab data such a chip would give: the gap's SPICE virtual silicon (``gap.silicon``: the
same operating points, noise and test set-up) on the **post-layout** view of the design, with the
light map's exposed junctions (``light.exposed`` under ``--shield pixels``: the column circuit's
sampler node and column line, the drawn AFE's nodes) as current sources on their own nodes, each
``area x J`` (J the photocurrent density of the pixel the column reads: the same responsivity as
its photodiode), on for the whole deck as the light map's are (``from_row``: from the row's start),
every node the map lights (driven ones included), of either sign (P+ in an n-well charges its node,
N+ discharges it). The fitter's elements do not enter: its ``readout_light_idle`` effect lights the
readout's signal nodes with the pattern ``open_readout`` gives the post-layout view, its response a
table of its own decks (``gap.idlelight``).

``check(design)`` diagnoses those data with ``gap.diagnose`` on the post-layout surrogate and sets
the effect's fitted open area against the layout's on one column's signal nodes.
"""
from __future__ import annotations

from dataclasses import replace


def exposed_signal_area(geos, shield: str = "pixels") -> dict:
    """Exposed junction area (m2) of one column's readout on the nodes where light leaves charge:
    its sampler node and column line (``DUALPIX_COL``, the primary's) and the AFE's signal nodes
    (the mean of ``AFE_P`` and ``AFE_S``); P+ and N+ separately (they draw opposite currents)."""
    from .light import SIGNAL_AFE, exposed
    col = [j for j in exposed(geos["DUALPIX_COL"], shield) if j.net in ("out_p", "col_p")]
    afe = [j for c in ("AFE_P", "AFE_S") for j in exposed(geos[c], shield) if j.net in SIGNAL_AFE]
    out = {"column_psd": sum(j.area_m2 for j in col if j.kind == "psd"),
           "column_nsd": sum(j.area_m2 for j in col if j.kind != "psd"),
           "afe_psd": sum(j.area_m2 for j in afe if j.kind == "psd") / 2,
           "afe_nsd": sum(j.area_m2 for j in afe if j.kind != "psd") / 2}
    out["total"] = sum(out.values())
    return out


def _lit(junctions, j_density: float):
    from .light import Junction
    return [Junction(j.net, j.kind, j.area_m2, j.area_m2 * j_density) for j in junctions]


def light_edit(design, geos, shield: str = "pixels", only=None, from_row: bool = False):
    """``edit(net, op) -> net`` for ``gap.silicon.simulate_case``: every column's exposed junctions as
    current sources at that column's pixel irradiance, on for the whole deck as the light map's are
    (``from_row``: from the row's start only, as ``readout_light`` does; ``only``: these nets alone)."""
    from ...circuits.testbench import timings
    from ...gap import circuit_edits as ce
    from ...gap.silicon import SUBS, _arr, _col_of
    from ...spice.netlist import Element
    from .light import afe_sources, bench_node, exposed
    n = design.secondary_per_pixel
    keep = (lambda js: js) if only is None else (lambda js: [j for j in js if j.net in only])
    col_js = keep(exposed(geos["DUALPIX_COL"], shield))
    afe_js = [keep(exposed(geos[c], shield)) for c in ("AFE_P", "AFE_S")]

    tm = timings(design, design.experiment.t_window)

    def during_row(e, arr):     # the bench clocks an AFE only in its row; a chip's resets it every row
        return replace(e, value=ce.pulse(tm[arr].row(0), tm[arr].t_stop - ce.EDGE, e.value)) if from_row else e

    def edit(net, op):
        top = []
        for s in SUBS:
            arr, col = _arr(s), _col_of(s)
            j = op["i"][s] / getattr(design, arr).photoactive_area
            mine = (col, f"in_col_{col[4:]}")
            for k, jn in enumerate(_lit(col_js, j)):
                node = bench_node(jn.net, n)
                if node in mine and jn.current_A > 0:
                    top.append(during_row(Element(f"Ilight_{col}_{k}", ("vdd", node) if jn.kind == "psd"
                                                  else (node, "0"), jn.current_A), arr))
            inner = [during_row(e, arr) for e in afe_sources([_lit(js, j) for js in afe_js])]
            net = ce.add_to_subckt(net, f"scafe_{col}", *inner) if inner else net      # none in the dark
        return replace(net, elements=net.elements + tuple(top))
    return edit


def virtual_measurement(post, nom, geos, seed: int = 7, shield: str = "pixels", backend: str = "batch",
                        only=None, from_row: bool = False) -> list:
    """Rows of one lab campaign of ``gap.silicon`` on the post-layout view ``post`` lit through ``shield``
    (``nom``: its surrogate, for the operating points' ranges), as a measured file gives them."""
    from ...gap.silicon import HEADER, _fmt, simulate_case
    rows, _ = simulate_case(post, nom, None, seed, backend=backend, edit=light_edit(post, geos, shield, only, from_row))
    return [{h: _fmt(r[h]) for h in HEADER[1:]} for r in rows]


def check(design, shield: str = "pixels", seed: int = 7, backend: str = "batch", only=None,
          from_row: bool = False) -> dict:
    """The diagnosis of the virtual measurement: best effect, its fitted junction area, the layout's."""
    from ...gap.diagnose import diagnose
    from ...gap.silicon import table_of
    from ...gap.store import load_nominal
    from . import chip_geometry
    from .overlay import post_layout_view
    post = post_layout_view(design)
    nom = load_nominal(post, backend=backend)
    geos = chip_geometry(design, ("DUALPIX_COL", "AFE_P", "AFE_S"))
    table = table_of(post, virtual_measurement(post, nom, geos, seed, shield, backend, only, from_row), "virtual measurement")
    r = diagnose(post, table, nom, seed=0)
    def fitted(effect, param):
        fit = next((x for x in r["ranking"] if x["effect"] == effect), None)
        return None if fit is None else fit["params"].get(param)
    return {"diagnosis": r, "best": r["best"], "verdict": r["verdict"],
            "a_junction_fit_m2": fitted("readout_light", "a_junction_m2"),
            "a_open_fit_m2": fitted("readout_light_idle", "a_open_m2"),
            "exposed": exposed_signal_area(geos, shield)}



def light_pattern(gf180) -> tuple:
    """(((node, kind, share of the open area), ...), open area m^2): the open junctions of one column's readout
    in the kit's drawn GF180 dual pixel and AFE (``gf180``: ``designs/dual_pixel_gf180.toml`` loaded;
    ``light.exposed`` under a pixel-only shield), on the nodes the reference design's macromodel AFE has (the column line, the sampling node, vm, x, c),
    averaged over the primary's and the secondary's AFE (the reference's C35 stand-in has no layer stack, so no
    light map of its own). A case scales the area by 0.5 - 4 (another shield's openings); stored with it."""
    from . import chip_geometry
    from .light import exposed
    geos = chip_geometry(gf180, ("DUALPIX_COL", "AFE_P", "AFE_S"))
    js = [(("col" if j.net == "col_p" else "in_col"), j.kind, j.area_m2)
          for j in exposed(geos["DUALPIX_COL"], "pixels") if j.net in ("col_p", "out_p")]
    js += [(j.net, j.kind, j.area_m2 / 2) for c in ("AFE_P", "AFE_S") for j in exposed(geos[c], "pixels")
           if j.net in ("vm", "x", "c")]
    acc = {}
    for node, kind, a in js:
        k = (node, "psd" if kind == "psd" else "nsd")
        acc[k] = acc.get(k, 0.0) + a
    tot = sum(acc.values())
    return tuple((n, k, a / tot) for (n, k), a in sorted(acc.items())), tot
