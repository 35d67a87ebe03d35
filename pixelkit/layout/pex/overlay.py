"""The post-layout view of a design: the extracted parasitics as an overlay on its netlists.

``post_layout_view(design)`` draws the design's dual pixel with its column circuits, extracts
them (``nets``, ``capacitance``) and returns the same design carrying a :class:`Parasitics`:
the generators then add the wiring capacitances to the subcircuits the simulations use, so every
command runs the schematic or the post-layout view of one design with one flag. What goes where:

- ``pix5t_primary`` / ``pix5t_secondary``: each coupling of a node of the subpixel (``fd``,
  ``pd``, ``sfo``) to ground or to a net that is one of its ports (``tg``, ``rst``, ``col`` ...);
  a coupling to a net the cell does not see (another subpixel's column line) is taken to ground.
  The three secondaries are drawn alike but sit among other neighbours: their mean is used.
- ``dualpix``: the couplings between the dual pixel's own lines (row lines, column lines,
  supplies): one row's share of every column-to-column and row-to-column coupling.
- the column line's lumped capacitance (``column.load``, in place of ``pixel.column_cap``): the
  other ``rows - 1`` dual pixels' share of the line (its total per dual pixel but its couplings to
  the dual pixel's other column lines, to ground) plus the column circuit's wiring; and
  (``column.line_couplings``) the other rows' share of each column-to-column coupling.
- ``scafe``: the drawn AFEs' wiring (``AFE_P``, ``AFE_S``; their mean) among the SC stage's nodes
  (``in``, ``vm``, ``x``, ``c``, ``out``, clocks, supplies); the op-amp's inner nodes as ground.
  Only in a view made with ``afe=True`` (``Parasitics.afe``; the default): a command that simulates
  no AFE (``array`` without ``--afe``) asks for the view without them, which is drawn and extracted
  without the AFEs and cached apart, and which every AFE's netlist and the light map refuse;
- resistance: every long line's end-to-end resistance (column lines over the array's rows, row
  lines over its columns) from its length, width and the stack's sheet resistance; reported,
  not simulated (``docs/post-layout.md``: at 90 mOhm/sq the column line's RC is below 1 ns).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

from .nets import AFE_NODES, GROUND

PIXEL_PORTS = ("vdd", "vpdr", "vrst", "ec", "tg", "rst", "rs", "col")
_MIN_C = 1e-19    # couplings below 0.1 aF are dropped


@dataclass(frozen=True)
class Parasitics:
    """Extracted wiring capacitances placed in the kit's subcircuits (F)."""
    cells: dict = field(default_factory=dict)       # subcircuit -> ((node, node, C), ...)
    column_cap: dict = field(default_factory=dict)  # "primary" / "secondary" -> lumped rest of the line (F)
    per_row: dict = field(default_factory=dict)     # figures per dual pixel: {"col_p": F, ...}
    resistance: dict = field(default_factory=dict)  # line -> Ohm
    source: str = ""
    column_pairs: tuple = ()                        # (col, col, F): the other rows' share of each coupling
    #: (bench node, kind, m2): the readout's signal-node junctions the drawn shield leaves open
    #: (``light.open_readout``: what gap's ``readout_light_idle`` lights)
    open_readout: tuple = ()
    #: whether the AFEs were drawn and extracted (``scafe``'s wiring, ``open_readout``)
    afe: bool = True

    def as_dict(self) -> dict:
        from dataclasses import asdict
        return asdict(self)

    def require_afe(self, what: str) -> None:
        """Refuse (an internal fault: the command asked for the wrong view) to serve ``what`` of the AFEs
        from a view extracted without them."""
        if not self.afe:
            raise ValueError(f"{what}: the post-layout view was extracted without the AFEs "
                             "(post_layout_view(design, afe=False)); a command that simulates an AFE needs afe=True")

    def node_wiring(self, which: str, node: str, a_sf: float | None = None) -> float:
        """Wiring capacitance (F) on ``node`` of ``which`` subpixel; couplings to nodes that follow FD
        through the source follower (``sfo``, ``col``) count (1 - a_sf) of themselves when a_sf is given."""
        total = 0.0
        for a, b, c in self.cells.get(f"pix5t_{which}", ()):
            if node not in (a, b):
                continue
            other = b if a == node else a
            follows = node == "fd" and other in ("sfo", "col") and a_sf is not None
            total += c * (1.0 - a_sf) if follows else c
        return total


def _local(net: str, inst: str, ports: dict) -> str | None:
    """The name of ``net`` inside instance ``inst`` ("p", "s0"): its own node, the port it reaches,
    or None (a net the cell does not see)."""
    if net.startswith(inst + "."):
        return net.split(".", 1)[1]
    return ports.get(net)


def _instance_ports(n_secondary: int) -> dict:
    """{instance: {dual-pixel net: subpixel port}} as ``circuits.dual_pixel`` wires them."""
    out = {"p": dict(zip(("vdd", "vpdr", "vrst", "ec_p", "tg_p", "rst_p", "rs_p", "col_p"), PIXEL_PORTS))}
    for k in range(n_secondary):
        out[f"s{k}"] = dict(zip(("vdd", "vpdr", "vrst", "ec_s", "tg_s", "rst_s", "rs_s", f"col_s{k}"), PIXEL_PORTS))
    return out


def place(cpl, n_secondary: int) -> dict:
    """The couplings of the dual pixel (``DUALPIX``, names as ``nets.py`` gives them) by subcircuit."""
    inst = _instance_ports(n_secondary)
    acc = {"pix5t_primary": {}, "pix5t_secondary": {}, "dualpix": {}}
    for (a, b), c in cpl.items():
        a, b = (GROUND if x == "vss" else x for x in (a, b))     # the substrate net is the simulations' 0
        if a == b:
            continue
        owners = {x.split(".", 1)[0] for x in (a, b) if "." in x}
        if not owners:      # two lines of the dual pixel (or one and ground)
            key = (a, b)
            acc["dualpix"][key] = acc["dualpix"].get(key, 0.0) + c
            continue
        for o in owners:    # a subpixel's node: in that subpixel, the other end its port or ground
            la, lb = _local(a, o, inst[o]), _local(b, o, inst[o])
            if a == GROUND:
                la = GROUND
            if b == GROUND:
                lb = GROUND
            la, lb = la or GROUND, lb or GROUND
            if la == lb:
                continue
            cell = "pix5t_primary" if o == "p" else "pix5t_secondary"
            share = 1.0 if o == "p" else 1.0 / n_secondary
            key = tuple(sorted((la, lb)))
            acc[cell][key] = acc[cell].get(key, 0.0) + c * share
    return {cell: tuple((a, b, c) for (a, b), c in sorted(d.items()) if c > _MIN_C) for cell, d in acc.items()}


def _line_resistance(geo, stack, net: str, layer: str) -> float:
    """End-to-end resistance (Ohm) of ``net``'s longest straight run on ``layer`` across the cell."""
    reg = geo.wires.get(layer, {}).get(net)
    if reg is None:
        return 0.0
    best = 0.0
    for p in reg.each():
        b = p.bbox()
        long_, short = max(b.width(), b.height()), min(b.width(), b.height())
        if short > 0:
            best = max(best, long_ / short)
    return best * stack.conductor(layer).sheet


#: the AFE's nodes the simulated ``scafe`` subcircuit has (its ports and its capacitors' nodes)


def place_afe(cpls) -> tuple:
    """The couplings of the drawn AFEs (``AFE_P``, ``AFE_S``: their mean, one ``scafe`` serves every
    column) among the nodes ``scafe`` has; the op-amp's inner nodes and the bias are taken as ground."""
    acc = {}
    for cpl in cpls:
        for (a, b), c in cpl.items():
            a, b = (x if x in AFE_NODES else GROUND for x in (a, b))
            if a != b:
                key = tuple(sorted((a, b)))
                acc[key] = acc.get(key, 0.0) + c / len(cpls)
    return tuple((a, b, c) for (a, b), c in sorted(acc.items()) if c > _MIN_C)


def build(design, pix_geo, col_geo, afe_geos=()) -> Parasitics:
    """The overlay from the extracted ``DUALPIX`` and ``DUALPIX_COL`` geometry (and the AFEs')."""
    from .capacitance import capacitances
    st = design.tech.stack
    n = design.secondary_per_pixel
    pix = capacitances(pix_geo, st)
    col = capacitances(col_geo, st)
    cols = {"primary": ["col_p"], "secondary": [f"col_s{k}" for k in range(n)]}
    per_row = {c: pix.total(c) for cs in cols.values() for c in cs}
    per_row.update({f"{w}.fd": pix.total("p.fd" if w == "primary" else "s0.fd") for w in ("primary", "secondary")})
    column_cap, resistance = {}, {}
    per_col = [c for cs in cols.values() for c in cs]
    for kind, names in cols.items():
        rows = getattr(design, kind).rows
        cell = [col.total(c) - pix.total(c) for c in names]   # the column circuit's wiring of the line
        own = [pix.total(c) - sum(pix.pair(c, o) for o in per_col if o != c) for c in names]
        column_cap[kind] = sum((rows - 1) * o + x for o, x in zip(own, cell)) / len(names)
        resistance[f"column line ({kind}, {rows} rows)"] = rows * max(
            _line_resistance(pix_geo, st, c, "metal4") for c in names)
    duals = design.primary.cols          # a row line crosses every dual pixel of the row
    for line in ("tg_p", "rst_p", "tg_s", "rst_s"):
        resistance[f"row line {line} ({duals} dual pixels)"] = duals * _line_resistance(pix_geo, st, line, "metal3")
    names = [c for cs in cols.values() for c in cs]
    pairs = tuple((a, b, (design.primary.rows - 1) * pix.pair(a, b))
                  for i, a in enumerate(names) for b in names[i + 1:] if pix.pair(a, b) > _MIN_C)
    cells = place(pix, n)
    if afe_geos:
        cells["scafe"] = place_afe([capacitances(g, st) for g in afe_geos])
    from .light import open_readout
    return Parasitics(cells, column_cap, per_row, resistance,
                      f"extracted from the drawn DUALPIX / DUALPIX_COL of {design.name} ({st.source})", pairs,
                      open_readout(col_geo, afe_geos, n) if afe_geos else (), bool(afe_geos))


_CACHE: dict = {}


def from_gds(design, gds, afe: bool = True) -> Parasitics:
    """The overlay extracted from the cells of ``gds`` (``DUALPIX``, ``DUALPIX_COL``, ``AFE_P``, ``AFE_S``:
    a layout the designer edited) instead of the drawing."""
    from . import AFE_CELLS, gds_geometry
    g = gds_geometry(design, gds, ("DUALPIX", "DUALPIX_COL", *(AFE_CELLS if afe else ())))
    p = build(design, g["DUALPIX"], g["DUALPIX_COL"], [g[c] for c in AFE_CELLS if afe])
    return replace(p, source=f"extracted from {gds} (cells DUALPIX / DUALPIX_COL{' / AFE_P / AFE_S' if afe else ''}) "
                             f"of {design.name} ({design.tech.stack.source})")


def layout_file(design):
    """The GDS the design names in ``[layout] gds`` (relative to the design file), or None."""
    from pathlib import Path
    if getattr(design, "layout", None) is None:
        return None
    return Path(design.source).parent / design.layout.gds


def _base(design, afe: bool) -> str:
    """The part of an extraction's cache key that is not the design's fields: the code that draws and
    extracts, the technology (whole), whether the AFEs are in it, and the bytes of the GDS the design names
    in ``[layout] gds`` (if any)."""
    import hashlib
    from pathlib import Path
    pkg = Path(__file__).resolve().parents[2]
    h = hashlib.sha256(repr((design.tech, afe)).encode())
    gds = layout_file(design)
    if gds is not None:
        from ...readfile import sha256_file
        h.update(sha256_file(gds, "layout.gds", "gds").encode())
    for sub in ("layout", "tech", "circuits"):
        for p in sorted((pkg / sub).rglob("*.py")) + sorted((pkg / sub).rglob("*.toml")):
            h.update(str(p.relative_to(pkg)).encode())
            h.update(p.read_bytes())
    return h.hexdigest()


def _key(base: str, design, paths) -> str:
    """Cache key of a design's extraction: ``_base`` and the design's values at ``paths``, the fields the
    drawing and the extraction read (``readtrace``): a field they do not read (a bias voltage) is not in it."""
    import hashlib
    from .readtrace import values
    return hashlib.sha256((base + values(design, paths)).encode()).hexdigest()


_READS: dict = {}


def _read_sets(base: str) -> list:
    """The read sets (each a frozenset of field paths) extractions under ``base`` have met, stored beside them."""
    import hashlib
    import json
    if base not in _READS:
        files = store().load(hashlib.sha256((base + " read sets").encode()).hexdigest())
        _READS[base] = [frozenset(tuple(p) for p in r) for r in json.loads(files["reads.json"])] if files else []
    return _READS[base]


def _add_read_set(base: str, reads) -> None:
    import hashlib
    import json
    sets = _read_sets(base)
    if frozenset(reads) not in sets:
        sets.append(frozenset(reads))
        store().save(hashlib.sha256((base + " read sets").encode()).hexdigest(),
                     {"reads.json": json.dumps([sorted(map(list, r)) for r in sets]).encode()})


def store():
    """The checked store of extractions (its refusals name an extraction-cache file)."""
    from ...cachestore import Store
    return Store("pex", "extraction-cache", "extracting again")


def _stored(key: str) -> Parasitics | None:
    import json
    files = store().load(key)
    if not files:
        return None
    d = json.loads(files["parasitics.json"])
    return Parasitics({k: tuple(tuple(x) for x in v) for k, v in d["cells"].items()}, d["column_cap"],
                      d["per_row"], d["resistance"], d["source"], tuple(tuple(x) for x in d["column_pairs"]),
                      tuple(tuple(x) for x in d["open_readout"]), d["afe"])


def _store(key: str, p: Parasitics) -> None:
    import json
    from dataclasses import asdict
    store().save(key, {"parasitics.json": json.dumps(asdict(p)).encode()})


def post_layout_view(design, afe: bool = True):
    """``design`` with its extracted parasitics (``design.post_layout``): from the GDS the design names in
    ``[layout] gds`` (a layout the designer edited and signed off with ``pixelkit signoff``), else from
    the kit's own drawing; a clear error when its
    technology has no stack or its layout does not match its netlist. ``afe=False``: without the
    AFEs' extraction (for commands that simulate no AFE; see ``Parasitics.afe``). Extractions are
    cached in ``$PIXELKIT_CACHE/pex`` (key: the code that draws and extracts it, the technology, ``afe`` and the
    design's fields the drawing and the extraction read, ``readtrace``: a bias voltage or a timing changed
    finds the extraction it had)."""
    from ...tech.stack import require_stack
    from . import AFE_CELLS, chip_geometry
    require_stack(design.tech)
    if getattr(design, "post_layout", None) is not None and design.post_layout.afe == afe:
        return design
    from .readtrace import reading
    design = replace(design, post_layout=None)
    base = _base(design, afe)
    for paths in _read_sets(base):
        key = _key(base, design, paths)
        if key not in _CACHE:
            found = _stored(key)
            if found is None:
                continue
            _CACHE[key] = found
        return replace(design, post_layout=_CACHE[key])
    gds = layout_file(design)
    with reading(design, skip=("tech", "post_layout")) as reads:
        if gds is not None:          # the designer's layout ([layout] gds), not the drawing
            found = from_gds(design, gds, afe)
        else:
            g = chip_geometry(design, ("DUALPIX", "DUALPIX_COL", *(AFE_CELLS if afe else ())))
            found = build(design, g["DUALPIX"], g["DUALPIX_COL"], [g[c] for c in AFE_CELLS if afe])
    key = _key(base, design, reads)
    _store(key, found)
    _add_read_set(base, reads)
    _CACHE[key] = found
    return replace(design, post_layout=found)
