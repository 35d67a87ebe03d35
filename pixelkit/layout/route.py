"""Routing over placed devices: full-width lines, vertical jogs and via stacks, each drawn
only where the canvas says it is free (the layers' spacing rules to every other net).

A cell's horizontal signals (row controls, supplies) are *lines* on one metal spanning the
cell's width, so cells abut into rows. A terminal (a metal1 pad) reaches its line through a
*jog*: a metal1 stub to a via position, a via stack to the jog metal, a vertical segment to
the line's height and a via onto the line. The router searches the line's height (within
the allowed bands) and the via position (along the pad's row) nearest the terminal first,
so lines sit next to what they drive. When nothing fits it raises :class:`RouteError`
naming the net and the cell.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from .canvas import Box, Canvas, box
from .rules import RuleError
from .primitives import METALS, pad_side, stack_shapes

STEP = 50   # nm: search step of line heights and via positions


class RouteError(RuleError):
    """No room to route a net: a layout rule error of the cell (rule ``route``)."""

    def __init__(self, cell: str, net: str, detail: str):
        self.cell, self.net = cell, net
        super().__init__("route", f"{cell} cell", f"no room to route net {net!r} ({detail})")


@dataclass
class Lines:
    """Horizontal lines of a cell: ``layer`` from x0 to x1, allowed within ``bands`` (y ranges)."""
    layer: str
    x0: int
    x1: int
    bands: list
    y: dict = field(default_factory=dict)   # net -> centre y

    def candidates(self, near: int, half: int, grid: int):
        """Line centres inside the bands, nearest ``near`` first."""
        out = []
        for lo, hi in self.bands:
            a, b = lo + half, hi - half
            if a > b:
                continue
            y = max(a, min(b, near))
            y = (y // grid) * grid
            out.append((abs(y - near), y))
            k = 1
            while True:
                moved = False
                for yy in (y - k * STEP, y + k * STEP):
                    if a <= yy <= b:
                        out.append((abs(yy - near), (yy // grid) * grid))
                        moved = True
                if not moved:
                    break
                k += 1
        return [y for _, y in sorted(set(out))]


def line_box(lt, lines: Lines, y: int) -> Box:
    w = lt.width(lines.layer)
    return box(lines.x0, y - w // 2, lines.x1, y - w // 2 + w)


def _stub(lt, pad: Box, xv: int) -> list[tuple[str, Box]]:
    """metal1 from the centre of ``pad`` along its row to a via pad at x = ``xv`` (the pad
    itself is not part of it: it is drawn already)."""
    s1 = pad_side(lt, "metal1")
    yc = pad.cy
    via_pad = box(xv - s1 // 2, yc - s1 // 2, xv - s1 // 2 + s1, yc - s1 // 2 + s1)
    if pad.x0 <= via_pad.x0 and via_pad.x1 <= pad.x1:
        return []
    return [("metal1", box(min(pad.cx, xv), yc - s1 // 2, max(pad.cx, xv), yc - s1 // 2 + s1)), ("metal1", via_pad)]


def _jog_shapes(lt, pad: Box, xv: int, yl: int, line_layer: str, jog_layer: str) -> list[tuple[str, Box]]:
    """Shapes of a jog from metal1 ``pad`` (via at x = ``xv`` on the pad's row) to a line at ``yl``."""
    yc = pad.cy
    out = _stub(lt, pad, xv) + [(lay, b) for lay, b in stack_shapes(lt, xv, yc, "metal1", jog_layer) if lay != "metal1"]
    w = pad_side(lt, jog_layer)   # as wide as its via pads: no notch between two close pads
    if yl != yc:
        out.append((jog_layer, box(xv - w // 2, min(yc, yl), xv - w // 2 + w, max(yc, yl))))
    out += [(lay, b) for lay, b in stack_shapes(lt, xv, yl, jog_layer, line_layer)]
    return out


def route_to_line(cv: Canvas, lt, lines: Lines, net: str, pad: Box, jog_layer: str = "metal2",
                  reach: int = 4000, label: str = "", pending: tuple = ()) -> int:
    """Connect metal1 ``pad`` (net ``net``) to the net's line, drawing the line first if the net
    has none. ``pending``: pads of nets still to route - a jog that would pass over one (and
    take the via position it needs) is tried only when nothing else fits. Returns the line's
    centre y."""
    for avoid in ((pending, ()) if pending else ((),)):
        y = _route(cv, lt, lines, net, pad, jog_layer, reach, label, avoid)
        if y is not None:
            return y
    raise RouteError(cv.name, net, f"no free {lines.layer} line height and {jog_layer} jog within "
                     f"{reach / 1000:g} um of the terminal at ({pad.cx / 1000:g}, {pad.cy / 1000:g}) um")


def _route(cv, lt, lines, net, pad, jog_layer, reach, label, avoid):
    w = lt.width(lines.layer)
    ys = [lines.y[net]] if net in lines.y else lines.candidates(pad.cy, w // 2, lt.grid)
    xs = sorted({pad.cx + d for d in range(-reach, reach + 1, STEP)}, key=lambda x: (abs(x - pad.cx), x))
    xs = [(x // lt.grid) * lt.grid for x in xs]
    ok_x = []
    for xv in xs:  # via positions along the pad's row whose stub and lower stack are free
        first = _jog_shapes(lt, pad, xv, pad.cy, lines.layer, jog_layer)
        first = [(lay, b) for lay, b in first if lay in ("metal1", "via1") or lay == jog_layer]
        if all(cv.free(lay, b, net) for lay, b in first):
            ok_x.append(xv)
    h = max(lt.space(lay, optional=True) or 0 for lay in METALS[:METALS.index(lines.layer) + 1]) // 2
    inside = [x for x in ok_x if lines.x0 + h + pad_side(lt, lines.layer) // 2 <= x <= lines.x1 - h - pad_side(lt, lines.layer) // 2]
    ok_x = inside     # jogs stay half a space inside the cell: cells abut
    space2 = lt.space(jog_layer)
    for yl in ys:
        lb = line_box(lt, lines, yl)
        if net not in lines.y and not cv.free(lines.layer, lb, net):
            continue
        for xv in ok_x:
            shapes = _jog_shapes(lt, pad, xv, yl, lines.layer, jog_layer)
            if avoid and any(b.gap(a) < space2 for lay, b in shapes if lay == jog_layer for a in avoid):
                continue
            if all(cv.free(lay, b, net) for lay, b in shapes):
                if net not in lines.y:
                    cv.add(lines.layer, lb, net)
                    lines.y[net] = yl
                    cv.label(f"{lines.layer}_label", lines.x0 + w, yl, label or net)
                for lay, b in shapes:
                    cv.add(lay, b, net)
                return yl
    return None


def route_all(cv: Canvas, lt, lines: Lines, terminals: dict, order: list, attempts: int = 12) -> None:
    """Route every net of ``terminals`` (net -> metal1 pad) to its line, in ``order``; when one
    fails, start again with it first (a net boxed in by the others gets the first pick)."""
    snap = cv.snapshot()
    order = list(order)
    last = None
    for _ in range(attempts):
        lines.y.clear()
        try:
            for i, net in enumerate(order):
                route_to_line(cv, lt, lines, net, terminals[net],
                              pending=tuple(terminals[n] for n in order[i + 1:]))
            return
        except RouteError as exc:
            last = exc
            cv.restore(snap)
            if order[0] == exc.net:
                break
            order.remove(exc.net)
            order.insert(0, exc.net)
    raise last


def stub_to_track(cv: Canvas, lt, net: str, pad: Box, x: int, top: str) -> None:
    """Connect metal1 ``pad`` to a vertical track on metal ``top`` at x: a metal1 stub along
    the pad's row, then a via stack at (x, pad row)."""
    shapes = _stub(lt, pad, x) + stack_shapes(lt, x, pad.cy, "metal1", top)
    bad = [lay for lay, b in shapes if not cv.free(lay, b, net)]
    if bad:
        raise RouteError(cv.name, net, f"the stack to the {top} track at x = {x / 1000:g} um is blocked on {bad[0]}")
    for lay, b in shapes:
        cv.add(lay, b, net)


def track(cv: Canvas, lt, net: str, layer: str, x: int, y0: int, y1: int, width: int = 0) -> Box:
    """A vertical track on ``layer`` centred on x from y0 to y1."""
    w = width or lt.width(layer)
    return cv.add(layer, box(x - w // 2, y0, x - w // 2 + w, y1), net)


def via_on(cv: Canvas, lt, net: str, x: int, y: int, bottom: str, top: str) -> None:
    """A via stack between two metals (pads on each) at (x, y), notches to its own net filled."""
    shapes = stack_shapes(lt, x, y, bottom, top)
    if any(cv.fillers(lay, b, net) is None for lay, b in shapes):
        raise RouteError(cv.name, net, f"a via stack {bottom} - {top} at ({x / 1000:g}, {y / 1000:g}) um is blocked")
    for lay, b in shapes:
        cv.add_filled(lay, b, net)


def stack_fits(cv: Canvas, lt, x: int, y: int, bottom: str, top: str, net: str) -> bool:
    return all(cv.fillers(lay, b, net) is not None for lay, b in stack_shapes(lt, x, y, bottom, top))

