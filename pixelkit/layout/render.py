"""Pictures of a layout: a 2D plot (matplotlib) and a 3D view of the layer stack (pyvista, off-screen)."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..fileio import atomic_target, commit  # noqa: E402

# layer name -> (colour, z bottom um, z top um) of a schematic cross-section
STACK = {"nwell": ("#4c72b0", -1.0, 0.0), "active": ("#55a868", 0.0, 0.05), "poly": ("#c44e52", 0.05, 0.3),
         "metal1": ("#dd8452", 0.9, 1.2), "metal2": ("#8172b3", 1.6, 1.9), "metal3": ("#da8bc3", 2.3, 2.6),
         "metal4": ("#ccb974", 3.0, 3.3), "shield": ("#937860", 4.0, 4.6)}


def _by_layer(cell, tech):
    polys = cell.get_polygons()
    out = {}
    for name in STACK:
        l_ = tech.layer(name)
        out[name] = [p.points for p in polys if (p.layer, p.datatype) == (l_.layer, l_.datatype)]
    return out


def plot_2d(cell, tech, path: Path, title: str) -> Path:
    fig, ax = plt.subplots(figsize=(6, 7))
    for name, pts_list in _by_layer(cell, tech).items():
        colour = STACK[name][0]
        alpha = 0.35 if name == "shield" else 0.7
        for k, pts in enumerate(pts_list):
            ax.fill(pts[:, 0], pts[:, 1], color=colour, alpha=alpha, lw=0.3,
                    label=name if k == 0 else None)
    ax.set_aspect("equal")
    ax.set_xlabel("x (um)")
    ax.set_ylabel("y (um)")
    ax.set_title(title)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)   # off the chip
    path, tmp = atomic_target(path)
    fig.savefig(tmp, dpi=110, format="png", bbox_inches="tight")
    plt.close(fig)
    return commit(path, tmp)


def _rectangles(points):
    """Exact rectangle decomposition of a Manhattan polygon: slice into horizontal bands."""
    import gdstk
    poly = gdstk.Polygon(points)
    ys = np.unique(np.round(points[:, 1], 6))
    xmin, xmax = points[:, 0].min(), points[:, 0].max()
    out = []
    for y0, y1 in zip(ys, ys[1:]):
        for piece in gdstk.boolean(poly, gdstk.rectangle((xmin, y0), (xmax, y1)), "and"):
            (a, b), (c, d) = piece.bounding_box()
            out.append((a, b, c, d))
    return out


def view_3d(cell, tech, path: Path) -> Path:
    import pyvista as pv
    import vtk
    pv.OFF_SCREEN = True
    vtk.vtkLogger.SetStderrVerbosity(vtk.vtkLogger.VERBOSITY_OFF)  # "bad X server connection": we render off-screen
    plotter = pv.Plotter(off_screen=True, window_size=(900, 700))
    for name, pts_list in _by_layer(cell, tech).items():
        colour, z0, z1 = STACK[name]
        boxes = [pv.Box(bounds=(x0, x1, y0, y1, z0, z1)) for pts in pts_list for x0, y0, x1, y1 in _rectangles(pts)]
        if boxes:
            plotter.add_mesh(pv.merge(boxes), color=colour, opacity=0.45 if name == "shield" else 1.0)
    plotter.enable_parallel_projection()
    plotter.view_vector((0.45, -1.0, 1.1))
    plotter.reset_camera()
    plotter.add_text("n-well (PD) | active | poly | metal1 - metal4 | shield (top metal)", font_size=9)
    path, tmp = atomic_target(path)
    plotter.screenshot(str(tmp))
    plotter.close()
    return commit(path, tmp)


def plot_exposure(result: dict, exposure: dict, path: Path, title: str) -> Path:
    """The chip's blocks outlined and the junction no metal covers filled in red, with the
    exposed area of each block in the legend. ``result``: the layout's (``size_um``,
    ``block_regions_um``)."""
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Rectangle
    w, h = result["size_um"]
    fig, ax = plt.subplots(figsize=(6, max(4.0, min(9.0, 6 * h / max(w, 1e-9)))))
    colours = {"pixel array": "#4c72b0", "column circuits": "#55a868", "AFE": "#8172b3", "periphery": "#937860"}
    for name, boxes in result["block_regions_um"].items():
        e = exposure[name]["exposed_m2"] * 1e12
        for k, (x0, y0, x1, y1) in enumerate(boxes):
            ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, lw=0.8,
                                   ec=colours.get(name, "k"), label=f"{name}: {e:.4g} um2 open" if k == 0 else None))
    polys = []
    for e in exposure.values():
        for p in e["region"].each():
            polys.append([(pt.x / 1000, pt.y / 1000) for pt in p.each_point_hull()])
    if polys:
        ax.add_collection(PolyCollection(polys, facecolor="#d62728", edgecolor="#d62728", lw=0.3))
    ax.set_xlim(-0.02 * w, 1.02 * w)
    ax.set_ylim(-0.02 * h, 1.02 * h)
    ax.set_aspect("equal")
    ax.set_xlabel("x (um)")
    ax.set_ylabel("y (um)")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)   # off the chip
    path, tmp = atomic_target(path)
    fig.savefig(tmp, dpi=110, format="png", bbox_inches="tight")
    plt.close(fig)
    return commit(path, tmp)


def plot_violation(gds, cell: str, where: str, tech, path: Path, title: str, margin: float = 3.0) -> Path:
    """The layers of ``cell`` around a DRC marker (``where``: the marker as the deck's report gives
    it, cell coordinates in um), the marker outlined in red."""
    import re
    import gdstk
    from .gdsfile import read_gdstk
    lib = read_gdstk(gds, "gds")
    c = next(x for x in lib.cells if x.name == cell)
    nums = [float(v) for v in re.findall(r"-?\d+(?:\.\d+)?", where)]
    xs, ys = nums[0::2], nums[1::2]
    x0, x1, y0, y1 = min(xs) - margin, max(xs) + margin, min(ys) - margin, max(ys) + margin
    window = gdstk.rectangle((x0, y0), (x1, y1))
    fig, ax = plt.subplots(figsize=(5, 5))
    polys = c.get_polygons()
    names = dict(STACK, mim_top=("#17becf", 0, 0), via4=("#000000", 0, 0))
    for name, (colour, _z0, _z1) in names.items():
        lay = tech.layer(name)
        mine = [p for p in polys if (p.layer, p.datatype) == (lay.layer, lay.datatype)]
        for k, p in enumerate(gdstk.boolean(mine, window, "and")):
            ax.fill(p.points[:, 0], p.points[:, 1], color=colour, alpha=0.5, lw=0.3, label=name if k == 0 else None)
    ax.plot(xs + xs[:1], ys + ys[:1], color="red", lw=2, label="marker")
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=6, loc="upper right")
    path, tmp = atomic_target(path)
    fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return commit(path, tmp)
