"""Maze routing on a grid of via positions, for cells whose nets cannot all be lines (the AFE).

The grid's pitch is a via pad plus the largest spacing of the routing metals, so two wires on
neighbouring grid lines keep every spacing rule, and each wire is as wide as a via pad (no
notch where a via lands). What is drawn already - devices, pads, lines, keep-outs, the shapes
of placed cells - blocks the grid points whose pad would come closer than the layer's spacing
to another net; the shapes of the net being routed are its targets. A device terminal (a
metal1 pad off the grid) gets a via and a metal2 landing on the pad before anything is routed
(so no net takes the room a later one needs to come up), and a short access wire from the
landing to a free grid point, checked with :meth:`Canvas.free`.

Each net is a tree grown terminal by terminal with A* (a step costs one pitch, more against
a layer's preferred direction, a via more); what one net draws blocks the next. A net that
finds no path is moved to the front (behind the guarded nets) and all are routed again; then
:class:`RouteError` names it.

A guarded net (``guards``: net -> shield net) takes the free grid points beside, over and under its
route as soon as it is routed, so no later net runs next to it; after every net, those still free
are drawn as the shield net's metal, each piece routed to the shield net (a piece that cannot reach
it is left empty).
"""
from __future__ import annotations

import heapq
from dataclasses import dataclass, field

from .canvas import Box, Canvas, box
from .primitives import METALS, VIAS, pad_side, square, stack_shapes
from .route import RouteError

#: preferred direction of each routing metal ("v" / "h"): a step across it costs more
PREFERRED = {"metal2": "v", "metal3": "h", "metal4": "v", "metal5": "h"}
STEP, CROSS, VIA = 10, 16, 24
#: a guarded net's extra cost per neighbour another net holds (0 on the retry when the cell does not route with it)
BESIDE = 8
BLOCKED = "*"
#: a guarded net keeps the grid points within NEAR pitches of its landings for its shield
NEAR = 1.15


@dataclass
class Terminal:
    """A shape of the net the route must reach: a metal1 device pad or a wire on a routing metal."""
    layer: str
    box: Box


@dataclass
class GridRouter:
    cv: Canvas
    lt: object
    layers: tuple                      # routing metals, bottom first
    area: Box                          # where the grid lies (grid pads stay inside)
    pitch: int = 0
    nets: dict = field(default_factory=dict)   # net -> [Terminal]
    #: guarded net -> its shield's net: the grid points around a guarded net's route are kept from every
    #: other net and filled with the shield's metal, tied to the shield's net (``_shield``)
    guards: dict = field(default_factory=dict)
    beside: int = 0

    def __post_init__(self):
        lt = self.lt
        self.w = max(pad_side(lt, m) for m in self.layers)
        if not self.pitch:
            self.pitch = lt.snap_up(self.w + max(lt.space(m) for m in self.layers))
        p, a = self.pitch, self.area
        self.x0, self.y0 = a.x0 + self.w // 2, a.y0 + self.w // 2
        self.nx = max(0, (a.x1 - self.w // 2 - self.x0) // p + 1)
        self.ny = max(0, (a.y1 - self.w // 2 - self.y0) // p + 1)

    # grid geometry ---------------------------------------------------------------------------
    def xy(self, i: int, j: int) -> tuple[int, int]:
        return self.x0 + i * self.pitch, self.y0 + j * self.pitch

    def pad(self, k: int, i: int, j: int) -> Box:
        x, y = self.xy(i, j)
        return square(x, y, self.w)

    def add_net(self, net: str, terminals) -> None:
        self.nets.setdefault(net, []).extend(terminals)

    # blockages -------------------------------------------------------------------------------
    def _build(self):
        self.owner = [dict() for _ in self.layers]          # (i, j) -> net | BLOCKED
        self.vowner = [dict() for _ in self.layers[:-1]]     # via between layer k and k+1
        for s in self.cv.all_shapes():
            self._mark(s.layer, s.box, s.net)

    def _range(self, lo: int, hi: int, origin: int, n: int):
        p = self.pitch
        a = max(0, (lo - origin) // p)
        b = min(n - 1, (hi - origin) // p + 1)
        return range(a, b + 1)

    def _mark(self, layer: str, b: Box, net: str) -> None:
        if net.startswith("#reserved"):
            return
        tag = BLOCKED if (net.startswith("#") or not net) else net
        if layer in self.layers:
            k = self.layers.index(layer)
            size, table = self.w, self.owner[k]
            space = self.lt.space(layer) + (self._extra(layer))
        elif layer in self._vias:
            k = self._vias.index(layer)
            size, table = self.lt.cut(layer), self.vowner[k]
            space = self.lt.space(layer)
        else:
            return
        reach = space + size // 2 + 1
        for i in self._range(b.x0 - reach, b.x1 + reach, self.x0, self.nx):
            for j in self._range(b.y0 - reach, b.y1 + reach, self.y0, self.ny):
                x, y = self.xy(i, j)
                if square(x, y, size).gap(b) >= space:
                    continue
                cur = table.get((i, j))
                if cur is None:
                    table[(i, j)] = tag
                elif cur != tag:
                    table[(i, j)] = BLOCKED

    def _extra(self, layer: str) -> int:
        """Extra spacing on the shield's layer (its wide-metal rule)."""
        if self.lt.tech.layout.aliases.get("shield") == layer and self.lt.has("shield.space"):
            return max(0, self.lt.nm("shield.space") - self.lt.space(layer))
        return 0

    @property
    def _vias(self):
        return [VIAS[a, b] for a, b in zip(self.layers, self.layers[1:])]

    def free_for(self, k: int, node, net: str) -> bool:
        o = self.owner[k].get(node)
        return o is None or o == net

    def via_free(self, k: int, node, net: str) -> bool:
        o = self.vowner[k].get(node)
        return o is None or o == net

    # access ----------------------------------------------------------------------------------
    def _landing(self, net: str, t: Terminal) -> Terminal:
        """A metal1 device pad: a via and a landing pad on the lowest routing metal, on the pad."""
        low = self.layers[0]
        shapes = [(lay, b) for lay, b in stack_shapes(self.lt, t.box.cx, t.box.cy, "metal1", low) if lay != "metal1"]
        if not all(self.cv.free(lay, b, net) for lay, b in shapes):
            raise RouteError(self.cv.name, net, f"no room for a via on its pad at ({t.box.cx / 1000:g}, "
                             f"{t.box.cy / 1000:g}) um")
        for lay, b in shapes:
            self.cv.add(lay, b, net)
        return Terminal(low, shapes[-1][1])

    def _access(self, net: str, t: Terminal, radius: int = 3):
        """[(node (k, i, j), shapes)] ways onto the grid from terminal ``t``: a node whose pad
        touches it (no shapes), or a straight or L-shaped wire to it."""
        k = self.layers.index(t.layer)
        b, w = t.box, self.w
        out = []
        p = self.pitch
        near = [(i, j) for i in self._range(b.x0 - radius * p, b.x1 + radius * p, self.x0, self.nx)
                for j in self._range(b.y0 - radius * p, b.y1 + radius * p, self.y0, self.ny)
                if self.free_for(k, (i, j), net)]
        near.sort(key=lambda n: self.pad(k, *n).gap(b))
        for i, j in near:
            if len(out) >= 8:      # the nearest ways on are enough
                break
            pad = self.pad(k, i, j)
            if _covers(b, pad, w):
                out.append((0, (k, i, j), []))
                continue
            x, y = self.xy(i, j)
            qx, qy = min(max(x, b.x0 + w // 2), b.x1 - w // 2), min(max(y, b.y0 + w // 2), b.y1 - w // 2)
            if b.w < w:
                qx = b.cx
            if b.h < w:
                qy = b.cy
            shapes = []
            if qx != x:
                shapes.append((t.layer, box(min(x, qx) - w // 2, y - w // 2, max(x, qx) + w // 2, y - w // 2 + w)))
            if qy != y:
                shapes.append((t.layer, box(qx - w // 2, min(y, qy) - w // 2, qx - w // 2 + w, max(y, qy) + w // 2)))
            if all(self.cv.fillers(lay, s, net) is not None for lay, s in shapes):
                out.append((abs(qx - x) + abs(qy - y), (k, i, j), shapes))
        out.sort(key=lambda a: a[0])
        return [(n, s) for _, n, s in out]

    # search ----------------------------------------------------------------------------------
    def _astar(self, net: str, sources: dict, targets: dict):
        """Cheapest path from any source node to any target node. ``sources`` / ``targets``:
        node -> extra cost. Returns the node list, source first."""
        if not targets:
            return None
        ii = [i for _, i, _ in targets]
        jj = [j for _, _, j in targets]
        i0, i1, j0, j1 = min(ii), max(ii), min(jj), max(jj)

        def h(node):     # grid steps to the targets' bounding box: never more than the cost left
            _, i, j = node
            return (max(i0 - i, 0, i - i1) + max(j0 - j, 0, j - j1)) * STEP

        heap = []
        best = {}
        for n, c in sources.items():
            best[n] = c
            heapq.heappush(heap, (c + h(n), c, n, None))
        came = {}
        nl = len(self.layers)
        while heap:
            f, g, node, prev = heapq.heappop(heap)
            if g > best.get(node, 1 << 60):
                continue
            if node in came:
                continue
            came[node] = prev
            if node in targets:
                path = [node]
                while came[path[-1]] is not None:
                    path.append(came[path[-1]])
                return path[::-1]
            k, i, j = node
            steps = []
            d = PREFERRED.get(self.layers[k], "")
            for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                ii, jj = i + di, j + dj
                if 0 <= ii < self.nx and 0 <= jj < self.ny and self.free_for(k, (ii, jj), net):
                    along = (d == "h") == (di != 0)
                    steps.append(((k, ii, jj), (STEP if along or not d else CROSS) + self._beside(net, k, ii, jj)))
            for kk in (k - 1, k + 1):
                if 0 <= kk < nl and self.free_for(kk, (i, j), net) and self.via_free(min(k, kk), (i, j), net):
                    steps.append(((kk, i, j), VIA))
            for n2, c in steps:
                g2 = g + c + targets.get(n2, 0)
                if g2 < best.get(n2, 1 << 60):
                    best[n2] = g2
                    heapq.heappush(heap, (g2 + h(n2), g2, n2, node))
        return None

    def _beside(self, net: str, k: int, i: int, j: int) -> int:
        """Extra cost of a guarded net's step onto (k, i, j): ``beside`` for each neighbouring point
        another net holds (the landings and access wires drawn before any route: the guard keeps
        only later nets away)."""
        if not self.beside or net not in self.guards:
            return 0
        mine = (None, net, self.guards[net], BLOCKED)
        return self.beside * sum(1 for n in ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1))
                                 if self.owner[k].get(n) not in mine)

    # drawing ---------------------------------------------------------------------------------
    def _draw(self, net: str, path: list) -> None:
        w = self.w
        runs, start = [], 0
        for a in range(1, len(path) + 1):
            if a == len(path) or path[a][0] != path[start][0]:
                runs.append(path[start:a])
                start = a
        for run in runs:
            k = run[0][0]
            xs = [self.xy(i, j) for _, i, j in run]
            # split a run at its bends into straight pieces
            piece = [xs[0]]
            for q in xs[1:]:
                if len(piece) >= 2 and (piece[0][0] != q[0] and piece[0][1] != q[1]):
                    self._seg(k, piece, net)
                    piece = [piece[-1]]
                piece.append(q)
            self._seg(k, piece, net)
        for a, b in zip(path, path[1:]):
            if a[0] != b[0]:
                lo = min(a[0], b[0])
                x, y = self.xy(a[1], a[2])
                via = self._vias[lo]
                self._put(via, square(x, y, self.lt.cut(via)), net)

    def _seg(self, k: int, pts, net: str) -> None:
        w = self.w
        x0, x1 = min(p[0] for p in pts), max(p[0] for p in pts)
        y0, y1 = min(p[1] for p in pts), max(p[1] for p in pts)
        self._put(self.layers[k], box(x0 - w // 2, y0 - w // 2, x1 - w // 2 + w, y1 - w // 2 + w), net)

    def _put(self, layer: str, b: Box, net: str) -> None:
        n = len(self.cv.shapes)
        if not self.cv.add_filled(layer, b, net):
            self.cv.add(layer, b, net)   # left for the deck to judge; never expected (grid spacing)
        for s in self.cv.shapes[n:]:     # the box and the fillers of its notches
            self._mark(s.layer, s.box, s.net)

    # the whole job -----------------------------------------------------------------------------
    def route(self, order=None, attempts: int = 6) -> None:
        """Route every net; with guarded nets, first with their detour cost ``BESIDE`` and, where the
        cell does not route so, again without it."""
        if self.guards:
            snap = self.cv.snapshot()
            self.beside = BESIDE
            try:
                return self._route_tries(list(order or self.nets), attempts)
            except RouteError:
                self.cv.restore(snap)
        self.beside = 0
        self._route_tries(list(order or self.nets), attempts)

    def _route_tries(self, order, attempts: int) -> None:
        snap = self.cv.snapshot()
        last = None
        for _ in range(attempts):
            try:
                self._route_all(order)
                return
            except RouteError as exc:
                last = exc
                self.cv.restore(snap)
                first = sum(1 for n in order if n in self.guards and n != exc.net)   # guarded nets stay first
                if exc.net in self.guards:
                    first = 0
                if order.index(exc.net) == first:
                    break
                order.remove(exc.net)
                order.insert(first, exc.net)
        raise last

    def _route_all(self, order) -> None:
        terms = {}
        for net in order:   # every device pad gets its landing first
            terms[net] = [self._landing(net, t) if t.layer == "metal1" else t for t in self.nets[net]]
        self._build()
        self.done = {}
        reserved = {}
        for net in order:
            self._route_net(net, terms[net])
            if net in self.guards:
                reserved[net] = self._reserve(net, self.guards[net], terms[net])
        for net, nodes in reserved.items():
            self._shield(self.guards[net], nodes)

    def _reserve(self, net: str, shield: str, terms=()) -> set:
        """The free grid points beside ``net``'s route (the eight around each of its points on its layer,
        the one over and the one under it) and beside its terminals (within a pitch of a landing, on its
        layer and the one over it: the landings sit off the grid), taken for ``shield``: no later net runs
        beside, over or under the guarded one."""
        out = set()

        def take(kk, ii, jj):
            if 0 <= ii < self.nx and 0 <= jj < self.ny and self.owner[kk].get((ii, jj)) is None:
                self.owner[kk][(ii, jj)] = shield
                out.add((kk, ii, jj))

        for k, i, j in self.done.get(net, ()):
            near = [(k, i + di, j + dj) for di in (-1, 0, 1) for dj in (-1, 0, 1) if di or dj]
            near += [(kk, i, j) for kk in (k - 1, k + 1) if 0 <= kk < len(self.layers)]
            for kk, ii, jj in near:
                take(kk, ii, jj)
        p = self.pitch
        for t in terms:
            if t.layer not in self.layers:
                continue
            k = self.layers.index(t.layer)
            for kk in (k, k + 1)[:len(self.layers) - k]:
                for i in self._range(t.box.x0 - 2 * p, t.box.x1 + 2 * p, self.x0, self.nx):
                    for j in self._range(t.box.y0 - 2 * p, t.box.y1 + 2 * p, self.y0, self.ny):
                        if self.pad(kk, i, j).gap(t.box) <= NEAR * p:
                            take(kk, i, j)
        return out

    def _shield(self, shield: str, nodes: set) -> None:
        """Metal of ``shield`` on the reserved ``nodes`` still free for it: each piece (points joined
        along the grid) drawn and routed to ``shield``'s tree; a piece that cannot reach it is left out
        (its points stay empty: the guarded net then keeps two pitches from its neighbours there)."""
        nodes = {n for n in nodes if self.free_for(n[0], n[1:], shield)}
        tree = {n: 0 for n in self.done.get(shield, ())}
        while nodes:
            piece, todo = set(), [nodes.pop()]
            while todo:
                k, i, j = todo.pop()
                piece.add((k, i, j))
                for n in ((k, i + 1, j), (k, i - 1, j), (k, i, j + 1), (k, i, j - 1)):
                    if n in nodes:
                        nodes.discard(n)
                        todo.append(n)
            snap = self.cv.snapshot()
            for k, i, j in piece:
                for n in ((k, i + 1, j), (k, i, j + 1)):
                    if n in piece:
                        self._seg(k, [self.xy(i, j), self.xy(*n[1:])], shield)
                self._put(self.layers[k], self.pad(k, i, j), shield)
            path = self._astar(shield, {n: 0 for n in piece}, tree) if tree else None
            if path is None:
                self.cv.restore(snap)
                self._build()
                continue
            self._draw(shield, path)
            tree.update({n: 0 for n in (*path, *piece)})

    def _route_net(self, net: str, terms: list) -> None:
        if len(terms) < 2:
            return
        tree = {}
        for n in self._on_net(net, terms[0]):
            tree[n] = 0
        first = None
        if not tree:
            first = self._access(net, terms[0])
            if not first:
                raise RouteError(self.cv.name, net, f"its terminal at ({terms[0].box.cx / 1000:g}, "
                                 f"{terms[0].box.cy / 1000:g}) um has no free grid point near it")
        rest = list(terms[1:])
        src_shapes = {}
        if first:
            for n, shapes in first:
                if n not in tree:
                    tree[n] = STEP * (sum(abs(b.w) + abs(b.h) for _, b in shapes) // max(1, self.pitch))
                    src_shapes[n] = shapes
        while rest:
            rest.sort(key=lambda t: min((abs(t.box.cx - self.xy(i, j)[0]) + abs(t.box.cy - self.xy(i, j)[1])
                                         for _, i, j in tree), default=0))
            t = rest.pop(0)
            on = self._on_net(net, t)
            if any(n in tree and tree[n] == 0 and n not in src_shapes for n in on):
                continue   # already touched by the tree
            acc = {}
            acc_shapes = {}
            for n in on:
                acc[n] = 0
                acc_shapes[n] = []
            if not acc:
                for n, shapes in self._access(net, t):
                    if n not in acc:
                        acc[n] = STEP * (sum(b.w + b.h for _, b in shapes) // max(1, self.pitch))
                        acc_shapes[n] = shapes
            path = self._astar(net, tree, acc)
            if path is None:
                raise RouteError(self.cv.name, net, f"no path on {'/'.join(self.layers)} to its terminal at "
                                 f"({t.box.cx / 1000:g}, {t.box.cy / 1000:g}) um")
            for lay, b in src_shapes.pop(path[0], []):
                self._put(lay, b, net)
            if src_shapes:   # the tree's first terminal is now reached through path[0]: drop the rest
                for n in src_shapes:
                    tree.pop(n, None)
                src_shapes.clear()
            for lay, b in acc_shapes.get(path[-1], []):
                self._put(lay, b, net)
            self._draw(net, path)
            for n in path:
                tree[n] = 0
        self.done[net] = {n for n, c in tree.items() if c == 0}

    def _on_net(self, net: str, t: Terminal) -> list:
        """Grid nodes on the terminal's layer whose pad touches the terminal."""
        if t.layer not in self.layers:
            return []
        k = self.layers.index(t.layer)
        out = []
        for i in self._range(t.box.x0 - self.w, t.box.x1 + self.w, self.x0, self.nx):
            for j in self._range(t.box.y0 - self.w, t.box.y1 + self.w, self.y0, self.ny):
                pad = self.pad(k, i, j)
                if pad.overlaps(t.box) and self.free_for(k, (i, j), net) and _covers(t.box, pad, self.w):
                    out.append((k, i, j))
        return out


def _covers(t: Box, pad: Box, w: int) -> bool:
    """The pad lies on the terminal wire well enough to join it without a notch: the pad's
    centre inside the wire, or the wire as wide as the pad along the overlap."""
    return t.x0 <= pad.cx <= t.x1 and t.y0 <= pad.cy <= t.y1


__all__ = ["GridRouter", "Terminal", "METALS"]
