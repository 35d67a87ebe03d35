"""A cell being drawn: rectangles on named layers, each tagged with its net, in integer nm.

Coordinates are whole nanometres on the technology's grid (the GF180MCU deck checks a
5 nm grid), so no floating-point rounding can put a vertex off grid. Every shape carries
the net it belongs to: :meth:`Canvas.free` tells whether a new shape keeps the layer's
spacing rule to every shape of another net (and does not leave a notch narrower than the
rule to a shape of its own net) - the router draws only where it is free. Placed child
cells contribute their shapes (with their nets renamed to the parent's) to that check
without being copied: the GDS keeps them as references.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import gdstk

NM = 1e-9


@dataclass(frozen=True)
class Box:
    x0: int
    y0: int
    x1: int
    y1: int

    def moved(self, dx: int, dy: int) -> "Box":
        return Box(self.x0 + dx, self.y0 + dy, self.x1 + dx, self.y1 + dy)

    def grown(self, d: int) -> "Box":
        return Box(self.x0 - d, self.y0 - d, self.x1 + d, self.y1 + d)

    @property
    def w(self) -> int:
        return self.x1 - self.x0

    @property
    def h(self) -> int:
        return self.y1 - self.y0

    @property
    def cx(self) -> int:
        return (self.x0 + self.x1) // 2

    @property
    def cy(self) -> int:
        return (self.y0 + self.y1) // 2

    def gap(self, o: "Box") -> float:
        """Euclidean distance between the two boxes (0 when they touch or overlap)."""
        dx = max(o.x0 - self.x1, self.x0 - o.x1, 0)
        dy = max(o.y0 - self.y1, self.y0 - o.y1, 0)
        return math.hypot(dx, dy)

    def overlaps(self, o: "Box") -> bool:
        return self.x0 < o.x1 and o.x0 < self.x1 and self.y0 < o.y1 and o.y0 < self.y1

    def touches(self, o: "Box") -> bool:
        return self.x0 <= o.x1 and o.x0 <= self.x1 and self.y0 <= o.y1 and o.y0 <= self.y1


def box(x0, y0, x1, y1) -> Box:
    return Box(min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1))


@dataclass(frozen=True)
class Shape:
    layer: str
    box: Box
    net: str


@dataclass(frozen=True)
class Label:
    layer: str
    x: int
    y: int
    text: str


@dataclass(frozen=True)
class Placement:
    cell: "Canvas"
    dx: int
    dy: int
    nets: dict          # child net -> parent net
    columns: int = 1
    spacing: int = 0    # x spacing of an array of ``columns`` instances
    name: str = ""
    rows: int = 1
    row_spacing: int = 0   # y spacing of an array of ``rows`` instances


class Canvas:
    """Shapes of one cell. ``rules`` gives the spacing (nm) of a layer, or None (a marker)."""

    def __init__(self, name: str, rules):
        self.name, self.rules = name, rules
        self.shapes: list[Shape] = []
        self.labels: list[Label] = []
        self.placements: list[Placement] = []
        self._seen: dict = {}               # layer -> own shapes and those of placed cells
        self.ports: dict = {}               # port name -> anything the parent needs (line y, track x)

    # drawing ------------------------------------------------------------------------------
    def add(self, layer: str, b: Box, net: str = "") -> Box:
        if layer not in self._seen:
            self.rules.tech.layer(layer)   # a layer the technology lacks is named now, not at export
        s = Shape(layer, b, net)
        self.shapes.append(s)
        self._seen.setdefault(layer, []).append(s)
        return b

    def block(self, layers, b: Box, why: str = "#light") -> None:
        """Keep the router off ``b`` on ``layers`` (nothing is drawn): ``#light`` (a light path,
        kept in every parent) or ``#reserved`` (a track left to the parent)."""
        for layer in layers:
            self._seen.setdefault(layer, []).append(Shape(layer, b, why))

    def label(self, layer: str, x: int, y: int, text: str) -> None:
        self.labels.append(Label(layer, x, y, text))

    def place(self, cell: "Canvas", dx: int, dy: int, nets: dict, columns: int = 1, spacing: int = 0,
              name: str = "", rows: int = 1, row_spacing: int = 0, register: bool = True) -> None:
        """Reference ``cell`` at (dx, dy) (``columns`` copies ``spacing`` apart, ``rows`` rows
        ``row_spacing`` apart); its port nets become ``nets[port]``, its other nets ``name.net``.
        ``register=False``: the copies are not seen by :meth:`free` (a large array the parent
        does not route over)."""
        self.placements.append(Placement(cell, dx, dy, dict(nets), columns, spacing, name, rows, row_spacing))
        if not register:
            return
        assert rows == 1, "an array of rows is placed unregistered"
        for k in range(columns):
            tag = f"{name or cell.name}{k if columns > 1 else ''}"
            for s in cell.all_shapes():
                if s.net.startswith("#reserved"):
                    continue   # tracks a child left free are the parent's to use
                net = s.net if s.net.startswith("#") else nets.get(s.net, f"{tag}.{s.net}" if s.net else "")
                self._seen.setdefault(s.layer, []).append(Shape(s.layer, s.box.moved(dx + k * spacing, dy), net))

    def snapshot(self):
        return (list(self.shapes), list(self.labels), list(self.placements),
                {k: list(v) for k, v in self._seen.items()})

    def restore(self, snap) -> None:
        self.shapes, self.labels, self.placements = list(snap[0]), list(snap[1]), list(snap[2])
        self._seen = {k: list(v) for k, v in snap[3].items()}

    def all_shapes(self) -> list[Shape]:
        """Own shapes (keep-outs included) and those of placed cells, in this cell's coordinates."""
        return [s for shapes in self._seen.values() for s in shapes]

    # checks -------------------------------------------------------------------------------
    def free(self, layer: str, b: Box, net: str, extra: int = 0) -> bool:
        """True when ``b`` on ``layer`` keeps the spacing rule (+ ``extra``) to other nets and
        either touches or keeps the rule to shapes of its own net."""
        return self.fillers(layer, b, net, extra) == []

    def fillers(self, layer: str, b: Box, net: str, extra: int = 0):
        """None when ``b`` comes closer than the rule to another net; else the boxes that fill
        the notches it would leave to shapes of its own net (empty when there are none)."""
        space = self.rules.space(layer, optional=True)
        if space is None:
            return []
        space += extra
        near = []
        cut = layer == "contact" or layer.startswith("via")
        x0, y0, x1, y1 = b.x0 - space, b.y0 - space, b.x1 + space, b.y1 + space
        for s in self._seen.get(layer, ()):
            o = s.box
            if o.x0 >= x1 or o.x1 <= x0 or o.y0 >= y1 or o.y1 <= y0:
                continue   # a space or more apart along x or y: no need for the distance
            g = o.gap(b)
            if g >= space:
                continue
            if s.net != net or not net or (cut and s.box != b):
                return None   # another net; or two cuts that would merge into one of the wrong size
            if g > 0:  # same net, apart but closer than the rule: a notch the deck would flag
                near.append(s.box)
        out = []
        for o in near:
            g = b.grown(space)   # only the part of the neighbour next to b: no fill along a long track
            o = Box(max(o.x0, g.x0), max(o.y0, g.y0), min(o.x1, g.x1), min(o.y1, g.y1))
            f = Box(min(o.x0, b.x0), min(o.y0, b.y0), max(o.x1, b.x1), max(o.y1, b.y1))
            if self.fillers(layer, f, net, extra) is None:
                return None
            out.append(f)
        return out

    def add_filled(self, layer: str, b: Box, net: str) -> bool:
        """Draw ``b`` and the fillers of its notches to its own net; False (nothing drawn) when
        it comes too close to another net."""
        f = self.fillers(layer, b, net)
        if f is None:
            return False
        self.add(layer, b, net)
        for x in f:
            self.add_filled(layer, x, net)   # a filler may leave a notch of its own: fill that too
        return True

    def shapes_on(self, layer: str) -> list[Shape]:
        return list(self._seen.get(layer, ()))

    # output -------------------------------------------------------------------------------
    def to_gdstk(self, tech, cells: dict) -> gdstk.Cell:
        """The GDS cell (shapes merged per layer; placements as references to ``cells``)."""
        cell = gdstk.Cell(self.name)
        by_layer: dict = {}
        for s in self.shapes:
            by_layer.setdefault(s.layer, []).append(s.box)
        for name in sorted(by_layer):
            lay = tech.layer(name)
            rects = [gdstk.rectangle((b.x0 * 1e-3, b.y0 * 1e-3), (b.x1 * 1e-3, b.y1 * 1e-3)) for b in by_layer[name]]
            for p in gdstk.boolean(rects, [], "or", precision=1e-4, layer=lay.layer, datatype=lay.datatype):
                cell.add(p)
        for lb in self.labels:
            lay = tech.layer(lb.layer)
            cell.add(gdstk.Label(lb.text, (lb.x * 1e-3, lb.y * 1e-3), layer=lay.layer, texttype=lay.datatype))
        for p in self.placements:
            ref = cells[p.cell.name]
            if p.columns > 1 or p.rows > 1:
                cell.add(gdstk.Reference(ref, (p.dx * 1e-3, p.dy * 1e-3), columns=p.columns, rows=p.rows,
                                         spacing=(p.spacing * 1e-3, p.row_spacing * 1e-3)))
            else:
                cell.add(gdstk.Reference(ref, (p.dx * 1e-3, p.dy * 1e-3)))
        return cell
