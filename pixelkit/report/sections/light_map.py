"""The light map: the junctions the shield leaves open, their photocurrent at the scene's irradiance and
the output error each array's AFE sees (SPICE), under the shield as drawn (the readout open, as on
[Thesis2019]'s chip) and under a full shield, by the geometric light and by the collection model's
(the design's own first; the modelled one not in the quick profile, nor without a [collection]
table); with a picture of where the light gets in."""
from __future__ import annotations

from . import Checked, Figure, Section, Table

TITLE = "Light map: what the shield leaves open"


def _picture(ctx, geo, path):
    import klayout.db as kdb
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from ...layout.pex.light import METALS
    d = geo.dbu * 1e6
    metal = kdb.Region()
    for m in METALS:
        for reg in geo.wires.get(m, {}).values():
            metal += reg
    fig, ax = plt.subplots(figsize=(5, 7))
    for kind, nets in geo.junctions.items():
        for net, reg in nets.items():
            for p in (reg - metal).each():
                pts = [(q.x * d, q.y * d) for q in p.each_point_hull()]
                ro = net.startswith(("col", "out", "nbias"))
                ax.fill(*zip(*pts), color="C3" if ro else ("C0" if kind == "pd_n" else "C1"), lw=0)
    x0, y0, x1, y1 = (v * 1e6 for v in geo.bbox)
    ax.add_patch(plt.Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, lw=0.8))
    ax.set_aspect("equal")
    ax.set_xlabel("x (um)")
    ax.set_ylabel("y (um)")
    ax.set_title("exposed junctions: photodiodes (blue), readout (red), other (orange)", fontsize=8)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


SHIELDS = ("pixels", "full")


def _maps(ctx, geos) -> tuple[dict, str | None]:
    """{light: {shield: light map}}: the design's own light first, then the other one (or why not)."""
    from ...layout.pex.light import light_map
    d = ctx.design
    own = d.light.model
    other = "modelled" if own == "geometric" else "geometric"
    out = {own: {s: light_map(d, s, ctx.backend, geos) for s in SHIELDS}}
    why = None
    if other == "modelled" and d.tech.collection is None:
        why = (f"technology {d.tech.name} has no [collection] table: no collection model of the readout cells "
               "(docs/light-collection.md)")
    elif other == "modelled" and ctx.quick:
        why = ("quick profile: the modelled light map (the collection model of the three readout cells, minutes the "
               "first time, cached after) is not run; the full profile shows it, as does `pixelkit lightmap DESIGN "
               "--light modelled`")
    else:
        ctx.progress("light map: the other light (%s)" % other)
        out[other] = {s: light_map(d, s, ctx.backend, geos, light=other) for s in SHIELDS}
    return out, why


def label(light: str, shield: str, own: str) -> str:
    return f"shield '{shield}', {light} light" + (" (the design's)" if light == own else "")


def build(ctx) -> Section:
    d = ctx.design
    if d.tech.stack is None:
        return Section.needs_input(TITLE, "a technology with [stack]", f"technology {d.tech.name} has no process stack: "
                                          "its nets cannot be extracted (docs/post-layout.md)")
    if d.scene is None:
        return Section.needs_input(TITLE, "a [scene] table", "the design has no [scene]: no irradiance to light the die with")
    from ...layout.pex import chip_geometry
    from ...verify.light import judge
    geos = chip_geometry(d, ("DUALPIX_COL", "AFE_P", "AFE_S"))
    geo = geos["DUALPIX_COL"]
    own = d.light.model
    by_light, why_not = _maps(ctx, geos)
    maps = by_light[own]
    tables = []
    for light, ms in by_light.items():
        for s, m in ms.items():
            name = f"light_map_{s}" if light == own else f"light_map_{s}_{light}"
            tables.append(Table(name, f"Exposed junctions, shield '{s}', {light} light ({m['irradiance_W_m2']:g} W/m2 "
                                      "on the die)",
                                ["cell", "net", "bench node", "junction", "area (um2)", "photocurrent (pA)"],
                                [[j["cell"], j["net"], j["node"], j["kind"], j["area_m2"] * 1e12, j["current_A"] * 1e12]
                                 for j in m["junctions"]]))
    tables.append(Table("light_map_error", "AFE output error from the light on the readout's junctions (SPICE)",
                        ["light", "shield", "column", "error (mV)", "read noise there (mV)", "error / read noise",
                         "error, light from the first row on (mV)", "that / read noise"],
                        [[light, s, c, v["error_V"] * 1e3, v["read_noise_V"] * 1e3, v["error_over_noise"],
                          v["error_from_row_V"] * 1e3, v["error_from_row_over_noise"]]
                         for light, ms in by_light.items() for s, m in ms.items() for c, v in m["columns"].items()]))
    fig = ctx.figure("light_map.png")
    _picture(ctx, geo, fig)
    bad = maps["pixels"]
    text = [f"Every diffusion and well of the drawn dual pixel with its column circuits that no metal covers, "
            f"with the photocurrent of the scene's headlight irradiance ({bad['irradiance_W_m2']:g} W/m2, the "
            "technology's QE over the scene's spectrum); each current put on its node in the dual-pixel bench "
            "with its AFE columns and the AFE outputs compared with the dark bench (ngspice): the error the light "
            "causes through the real readout. 'pixels' is the shield as drawn (over the subpixels, the readout "
            "open, as on the chip of [Thesis2019], which failed with light on its readout); 'full' leaves only the "
            "pixels' light openings.",
            "Two lights (docs/light-collection.md): 'geometric' lights each junction by its open area x the "
            "technology's QE; 'modelled' takes each readout junction's current from the collection model of its "
            "cell, where every diffusion of a node the bench carries collects the carriers generated anywhere in "
            "the cell, under the metal too (tens of pA where the geometric light gives tenths). The design uses "
            f"the {own} light (light.model); both are judged against the same limit"
            + (f"; the {'modelled' if own == 'geometric' else 'geometric'} light is not shown: {why_not}."
               if why_not else "."),
            f"Shield as drawn, {own} light: {bad['readout_area_m2'] * 1e12:.2f} um2 of readout junctions open, the "
            f"worst column error {bad['worst_error_over_noise']:.2g} x its read noise; full shield: "
            f"{maps['full']['worst_error_over_noise']:.2g} x"
            + "".join(f"; {light} light: {ms['pixels']['worst_error_over_noise']:.2g} x drawn, "
                      f"{ms['full']['worst_error_over_noise']:.2g} x full" for light, ms in by_light.items()
                      if light != own)
            + ". Not counted: light through the gates into the channels (collected by the devices' sources and "
            "drains), and a bright source's light spreading to its neighbour pixels' storage nodes (docs/light-collection.md).",
            "The light is switched on from the dark state at the frame's start and stays on through each array's "
            "own exposure (the design's t_int: the readout idle, its samplers open and its AFE unclocked) and the "
            "first row's read; lit from the first row's start only (what a readout clocked through the exposure "
            f"keeps), the worst error is {max(v['error_from_row_over_noise'] for v in bad['columns'].values()):.2g} x "
            "the read noise. The AFE's reset erases what its nodes gathered while idle as far as the ideal charge "
            "analysis goes, and the charge its island collects after the reset is microvolts on C13 under the "
            "geometric light; under the modelled light's hundredfold currents part of the idle's drift survives "
            "the read (docs/post-layout.md). Constant light sources would start the bench at its lit operating "
            "point, the floating nodes at their junctions' clamp: hundreds of millivolts that a readout reset every "
            "frame never reaches."]
    limit = d.light.max_readout_error
    verdicts = {(light, s): judge(m["columns"], limit) for light, ms in by_light.items() for s, m in ms.items()}
    against = f"{limit} the read noise there" if limit.strip().endswith("x") else limit
    text.insert(0, f"Verdict (pixelkit lightmap's, each column's AFE output error against the design's limit, "
                f"light.max_readout_error = {against}): "
                + "; ".join(f"{label(light, s, own)} {v['verdict']}"
                            + (f" (beyond it: {', '.join(v['failed'])})" if v["failed"] else "")
                            for (light, s), v in verdicts.items()) + ".")
    data = {**maps, "light": own, "other_light": {k: v for k, v in by_light.items() if k != own},
            "other_light_why_not": why_not,
            "verdict": {label(light, s, own): {k: v[k] for k in ("verdict", "limit", "failed")}
                        for (light, s), v in verdicts.items()}}
    return Section(TITLE, text=text, tables=tables,
                   figures=[Figure(fig.name, "Exposed junctions of DUALPIX_COL under the shield as drawn")],
                   checked=[Checked("light_map.worst_error_over_noise_pixels", bad["worst_error_over_noise"], "1",
                                    tol_rel=0.05),
                            Checked("light_map.readout_area_pixels_m2", bad["readout_area_m2"], "m2", tol_rel=0.01)],
                   data=data)
