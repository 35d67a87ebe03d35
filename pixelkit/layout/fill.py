"""Dummy fill for the foundry's density rules (``pixelkit layout --fill``), kept off the light path.

GF180MCU's density deck (fd_pv ``density.drc``) asks, over the whole die, Poly2 >= 14 % (PL.8, drawn
poly only: its dummy datatype does not count) and Metal1 - Metal5 >= 30 % each (M1.4 ... M5.4, drawn
and dummy). The kit's pixels and readout draw far less of the lower layers (the 2 x 2 chip with its
AFEs: poly 2.6 %, metal1 0.7 %, metal2 8.2 %, metal3 3.8 %; metal4 43.5 %, metal5 86.9 %), so a chip
needs fill. Here it is a cell ``<top>_FILL`` placed in the chip: squares of each layer whose coverage
is under the rule's figure, on a grid, wherever they keep

- ``CLEARANCE`` from every drawn shape of their layer (a fill square is a floating conductor: nearer, it
  adds coupling to the wires; 0.6 um, twice the foundry's spacing rule of 0.23 - 0.28 um),
- ``LIGHT_CLEARANCE`` from the light path: the photodiode wells the top metal leaves open (every layer;
  fill there would shade the pixel),
- poly also ``POLY_CLEARANCE`` from COMP, the n-wells (the pixels' photodiodes and the P-channel
  devices' wells), the resistor and MIM markers (floating poly over COMP would be a gate; over a well it
  is left out to keep the photodiode clean),
- ``EDGE`` inside the chip's boundary.

Metal fill goes on the foundry's dummy datatype (``<layer>_fill`` in the technology's ``[layers]``:
Metal1 34/4 ...), which the density deck counts and the LVS decks treat as floating metal; poly fill on
Poly2 itself (the deck's PL.8 counts only drawn poly). The extraction counts every fill square as a
floating conductor (``pex.nets``: ``~<layer>.<k>``; ``pex.capacitance.float_out``).
"""
from __future__ import annotations

from pathlib import Path

#: coverage the density deck asks per layer (fd_pv density.drc: PL.8, M1.4 - M5.4), a little above
TARGET = {"poly": 0.14, "metal1": 0.30, "metal2": 0.30, "metal3": 0.30, "metal4": 0.30, "metal5": 0.30}
SIZE = {"poly": 2.0}          # um: side of a fill square (metals METAL_SIZE)
SPACE = {"poly": 0.5}         # um between squares (metals METAL_SPACE)
METAL_SIZE, METAL_SPACE = 2.5, 0.5
CLEARANCE = 0.6               # um to drawn shapes of the layer
POLY_CLEARANCE = 0.5          # um from poly fill to COMP, wells, markers
LIGHT_CLEARANCE = 2.0         # um from the open photodiode wells
EDGE = 1.0                    # um inside the chip's boundary


def coverage(layout, cell, tech) -> dict:
    """{layer: fraction of the cell's extent} of each density layer (drawn and fill, as the deck counts)."""
    import klayout.db as kdb
    area = cell.bbox().area()
    out = {}
    for name in TARGET:
        reg = _region(layout, cell, tech, name)
        if name != "poly":
            reg += _region(layout, cell, tech, f"{name}_fill")
        out[name] = reg.merged().area() / area if area else 0.0
    return out


def _region(layout, cell, tech, name):
    import klayout.db as kdb
    if name not in tech.layout.layers and name not in tech.layout.aliases:
        return kdb.Region()
    lay = tech.layer(name)
    idx = layout.find_layer(lay.layer, lay.datatype)
    return kdb.Region(cell.begin_shapes_rec(idx)).merged() if idx is not None else kdb.Region()


def fill(gds: Path, top: str, tech) -> dict:
    """Add ``<top>_FILL`` to cell ``top`` of ``gds`` (rewritten in place, renamed into place) with fill on
    every layer under its density target; the coverage before and after, and the squares placed."""
    import klayout.db as kdb
    from ..fileio import atomic_target, commit
    layout = kdb.Layout()
    layout.read(str(gds))
    cell = layout.cell(top)
    before = coverage(layout, cell, tech)
    um = 1 / layout.dbu
    chip = kdb.Region(cell.bbox()).sized(-int(EDGE * um))
    open_pd = _region(layout, cell, tech, "pd_marker") - _region(layout, cell, tech, "metal5")
    light = open_pd.sized(int(LIGHT_CLEARANCE * um))
    holder = layout.create_cell(f"{top}_FILL")
    placed = {}
    for name, target in TARGET.items():
        if before[name] >= target:
            continue
        drawn = _region(layout, cell, tech, name)
        free = chip - drawn.sized(int(CLEARANCE * um)) - light
        if name == "poly":
            for other in ("active", "nwell", "res_marker", "mim_marker", "sab"):
                free -= _region(layout, cell, tech, other).sized(int(POLY_CLEARANCE * um))
            lay = tech.layer("poly")
        else:
            if f"{name}_fill" not in tech.layout.layers:
                continue
            lay = tech.layer(f"{name}_fill")
        size, space = SIZE.get(name, METAL_SIZE), SPACE.get(name, METAL_SPACE)
        square = layout.create_cell(f"FILL_{name.upper()}")
        li = layout.layer(lay.layer, lay.datatype)
        s = int(round(size * um))
        square.shapes(li).insert(kdb.Box(0, 0, s, s))
        g = int(round(space * um / 2))
        n0 = holder.child_instances()
        holder.fill_region(free, square.cell_index(), kdb.Box(-g, -g, s + g, s + g), kdb.Point(0, 0))
        placed[name] = holder.child_instances() - n0
    cell.insert(kdb.CellInstArray(holder.cell_index(), kdb.Trans()))
    after = coverage(layout, cell, tech)
    path, tmp = atomic_target(Path(gds))
    layout.write(str(tmp))
    commit(path, tmp)
    return {"cell": holder.name, "before": before, "after": after, "squares": placed,
            "rules": {k: v for k, v in TARGET.items()}}
