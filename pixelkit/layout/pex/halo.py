"""A bright source's halo: what the storage nodes of a lit pixel's neighbours collect
(docs/light-collection.md, "A bright source's halo").

The collection model's cell repeats: every pixel lit alike. A headlight imaged on one dual pixel lights
that cell alone; the carriers its light generates diffuse to the neighbours' junctions too. By
linearity and the array's translation symmetry, what the junction j of the cell at offset d from the
lit cell collects is the integral of the lit cell's generation G against psi^(0)_j(r - a_d), the
collection probability of the origin's junction j with every other cell's junctions collecting
(``physics.collection.solve_bloch``): Bloch solves of the one cell on the M x M wavevectors of the
Brillouin zone give it exactly for an M x M supercell of cells (:data:`CELLS`), the layers below the grid
joined at each wavevector's own decay length. Their sum over the supercell is the periodic model's
figure (every pixel lit): ``Halo.periodic``, held equal to ``collection.response``'s.

The lit cell's generation is the periodic light field's (``physics.lightfield``) in one cell: the light
the shield's openings of the lit cell let in, redistributed under the shield as in the periodic array
(the light a lit cell sends under its neighbours' shield comes back from its own neighbours there:
what crosses the cell's edge, a few microns of the 24 um pitch, is folded into the cell).

Per wavelength and storage node, :class:`Halo` holds the electrons collected per photon incident on the
lit cell, at each offset; :func:`figures` turns them, over a spectrum, into GSE-like ratios (the lit
photodiode's responsivity over the storage node's), as the bright-source table uses them.
"""
from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

#: the supercell the Bloch solves sample (the lit cell and its eight neighbours, then their images 3 cells on)
CELLS = (3, 3)
_CODE = ("layout/pex/halo.py",)


@dataclass
class Halo:
    """Per wavelength: electrons collected per photon incident on the lit cell by each storage node of the
    cell at offset (i, j) cells from it (``eta["i,j"][net]``), and their sum over the supercell (``periodic``)."""
    wavelength_m: np.ndarray
    cells: tuple
    eta: dict
    periodic: dict

    def to_json(self) -> str:
        return json.dumps({"wavelength_m": self.wavelength_m.tolist(), "cells": list(self.cells),
                           "eta": {d: {n: np.asarray(v).tolist() for n, v in e.items()} for d, e in self.eta.items()},
                           "periodic": {n: np.asarray(v).tolist() for n, v in self.periodic.items()}})

    @classmethod
    def from_json(cls, text: str) -> "Halo":
        d = json.loads(text)
        return cls(np.array(d["wavelength_m"]), tuple(d["cells"]),
                   {k: {n: np.array(v) for n, v in e.items()} for k, e in d["eta"].items()},
                   {n: np.array(v) for n, v in d["periodic"].items()})

    def at(self, i: int, j: int) -> dict:
        return self.eta[f"{i},{j}"]


def halo(design, geo=None, cells: tuple = CELLS, say=None, grid: float | None = None,
         step: float | None = None) -> Halo:
    """The halo of ``design``'s dual pixel (cached by geometry, light and ``cells``; ``grid``, ``step``: as
    ``collection.response``)."""
    from ...physics import collection as pc, lightfield as lf, silicon as si
    from . import collection as cl
    lt = design.light
    h = grid or lt.grid
    geo = geo if geo is not None else cl.pixel_geometry(design)
    sil = cl.silicon(design, geo, h, lt.depth)
    fds = [k + 1 for k, n in enumerate(sil.nets) if n.endswith(".fd")]
    wl = cl.wavelengths(design, step)
    n_ox = cl.require(design).dielectric_index
    need = {float(w): cl.ratio(h, n_ox, w) for w in wl}
    opt = {r: cl.optics(design, geo, h / r, None, "all", False, sil.grid.ny * r) for r in sorted(set(need.values()))}
    key = cl._digest("halo", cl._code_hash((*cl._CODE, *_CODE)), tuple(cells), sil.grid.h, sil.nets, sil.grid.z,
                     sil.labels, sil.n_type, sil.substrate, wl, design.temperature,
                     *[(o.shield, o.modal, o.metals, o.shield_z, o.shield_thickness, o.n_dielectric)
                       for o in opt.values()])
    files = cl._store().load(key)
    if files:
        return Halo.from_json(files["halo.json"].decode())
    if say:
        say(f"halo of {geo.top}: {len(fds)} storage nodes, {cells[0]} x {cells[1]} Bloch wavevectors")
    bloch = pc.solve_bloch(sil.grid, sil.labels, sil.n_type, sil.substrate, pc.bloch_wavevectors(sil.grid, cells), fds)
    offsets = [(i, j) for j in range(-(cells[1] // 2), cells[1] - cells[1] // 2)
               for i in range(-(cells[0] // 2), cells[0] - cells[0] // 2)]
    eta = {f"{i},{j}": {sil.nets[k - 1]: np.zeros(wl.size) for k in fds} for i, j in offsets}
    for n, w in enumerate(wl):
        r = need[float(w)]
        ab = lf.absorbed(opt[r], float(w), complex(si.index(w, design.temperature)),
                         float(si.alpha(w, design.temperature)), sil.grid.z, r)
        # the cell at offset d from the lit one collects what the origin's collects of light at -d
        got = pc.neighbour_collection(bloch, cells, ab.voxels, ab.deep, [(-i, -j) for i, j in offsets])
        for i, j in offsets:
            for k in fds:
                eta[f"{i},{j}"][sil.nets[k - 1]][n] = got[(-i, -j)][k]
        if say:
            say(f"halo: {w * 1e9:.0f} nm")
    periodic = {sil.nets[k - 1]: sum(e[sil.nets[k - 1]] for e in eta.values()) for k in fds}
    out = Halo(wl, tuple(cells), eta, periodic)
    cl._store().save(key, {"halo.json": out.to_json().encode()})
    return out


def figures(design, resp, hal: Halo, spectrum) -> dict:
    """Over ``spectrum``, per array, GSE-like ratios as ``lightfigures.figures`` gives the periodic model's (each
    subpixel's photodiode responsivity, lit everywhere, over its storage node's; the secondaries' mean): of the
    lit cell's own storage node with its neighbours dark (``gse_alone``), of the neighbour whose storage node
    collects most of the lit cell's light (``gse_neighbour``; ``neighbour``: its offset in cells) and of the
    eight neighbours' together (``gse_all_neighbours``)."""
    from ...physics.photo import responsivity
    from .lightfigures import nets_of, weighted

    def r_of(curve):
        rr = responsivity(hal.wavelength_m, curve)
        return spectrum.mean(lambda w: np.interp(w, hal.wavelength_m, rr, left=0.0, right=0.0))
    nets = nets_of(resp)
    out = {}
    for kind, pairs in (("primary", [nets["primary"]]), ("secondary", nets["secondary"])):
        r_pd = [weighted(resp, pd, spectrum) for pd, _ in pairs]

        def gse(offsets):
            got = [sum(r_of(hal.eta[d][fd]) for d in offsets) for _, fd in pairs]
            return float(np.mean([p / g if g > 0 else np.inf for p, g in zip(r_pd, got)]))
        ring = [d for d in hal.eta if d != "0,0"]
        each = {d: gse([d]) for d in ring}
        worst = min(each, key=each.get)
        out[kind] = {"gse_alone": gse(["0,0"]), "gse_neighbour": each[worst],
                     "neighbour": tuple(int(x) for x in worst.split(",")), "gse_all_neighbours": gse(ring)}
    return out
