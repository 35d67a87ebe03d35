"""The light-collection model on the drawn dual pixel: its layout's silicon and metals, per wavelength
and per junction the collected electrons per incident photon.

From the dual pixel as drawn (``DUALPIX``, nets matched to the netlist by ``nets.net_geometry``), an
infinite array of identical cells (periodic sides: the pixel and its neighbours):

- **silicon** (``physics.collection``): every junction's collecting region - a photodiode's or a
  PMOS n-well, an N+ diffusion in the substrate, a P+ diffusion in a well - is its drawn shape grown
  by the sidewall depletion width and deepened by the bottom one, both from the junction's own
  capacitance model at its bias (W = eps_Si / C_j(V) under the junction, eps_Si x_j / C_jsw(V) beside
  it, the depletion approximation's C = eps / W: the photodiode's from ``[photodiode]``, a MOS
  diffusion's from ``[mos]``); an n-well's interior is quasi-neutral n-type silicon (holes); a
  substrate tap is a sink. Junction depths, diffusion lengths, surface recombination and the
  substrate from the technology's ``[collection]``.
- **light** (``physics.lightfield``, ``physics.aperture``): the top metal (the shield) and the lower
  metals at their heights (the ``[stack]``, or ``[collection.metals]``), the secondaries' mask
  openings by the modal method, the primary's by Kirchhoff.
- **absorption** by wavelength (``physics.silicon``, [Green2008]) at the design's temperature.

Out of it (:class:`Response`): per wavelength, for each photodiode and floating diffusion, the
electrons collected per photon incident on the cell, the rest of the junctions together, and the
light's bookkeeping. The collection maps (one solve per junction) are cached by the silicon's
geometry and parameters, the optical results by the light's description (``$PIXELKIT_CACHE/light``).
"""
from __future__ import annotations

import hashlib
import io
import json
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ...errors import MISSING, ConfigError

EPS_SI = 11.7 * 8.8541878128e-12
CELL = "DUALPIX"
#: openings with both sides at most this wide are solved by the modal method, wider ones by Kirchhoff
MODAL_MAX = 3e-6
#: the nets whose collection is solved one by one (the rest collect together)
OWN = (".pd", ".fd")
REST = "other junctions"
#: the code the cached results depend on: the collection maps, and the responses (the light too)
_MAPS_CODE = ("physics/collection.py", "layout/pex/collection.py")
_CODE = (*_MAPS_CODE, "physics/lightfield.py", "physics/aperture.py", "physics/silicon.py",
         "physics/data/silicon_green2008.csv")


def require(design):
    """The technology's ``[collection]`` table, or a clear error naming it."""
    c = design.tech.collection
    if c is None:
        raise ConfigError(design.tech.source, "collection", MISSING,
                          f"a [collection] table in technology {design.tech.name} for the light-collection model "
                          "(light.model = \"modelled\"): the silicon's diffusion lengths, surface recombination and "
                          "junction depths (docs/technology-file.md, section [collection])")
    if design.tech.stack is None and not c.metals:
        raise ConfigError(design.tech.source, "collection.metals", MISSING,
                          "the metals' heights ([collection.metals.<layer>] z and thickness) or a [stack]")
    return c


def pixel_geometry(design, gds: Path | None = None):
    """``nets.NetGeometry`` of the dual pixel, drawn from ``design`` (or read from ``gds``)."""
    import tempfile
    from ..flow import write_gds
    from ..library import build_library
    from .nets import net_geometry
    if gds is not None:
        return net_geometry(gds, CELL, design)
    with tempfile.TemporaryDirectory(prefix="pixelkit-light-") as tmp:
        path = write_gds(build_library(design), Path(tmp) / f"{design.name}.gds")
        return net_geometry(path, CELL, design)


# ---------------------------------------------------------------------------------------- rasters

def _boxes(region, dbu):
    import klayout.db as kdb
    out = []
    for poly in region.each_merged():
        for t in poly.decompose_trapezoids(kdb.Polygon.TD_htrapezoids):
            b = t.bbox()
            out.append((b.left * dbu, b.bottom * dbu, b.right * dbu, b.top * dbu))
    return out


def _overlap(lo, hi, h, n):
    """Length of [lo, hi] in each of the n cells of size h of a period n h (images wrapped)."""
    L = n * h
    edges = np.arange(n) * h
    out = np.zeros(n)
    for k in range(int(np.floor(lo / L)), int(np.floor((hi - 1e-15) / L)) + 1):
        a, b = lo - k * L, hi - k * L
        out += np.clip(b - edges, 0, h) - np.clip(a - edges, 0, h)
    return out


def coverage(region, dbu, h, nx, ny) -> np.ndarray:
    """Fraction of each cell (ny, nx) of a periodic grid of spacing ``h`` that ``region`` covers."""
    cov = np.zeros((ny, nx))
    for x0, y0, x1, y1 in _boxes(region, dbu):
        cov += np.outer(_overlap(y0, y1, h, ny), _overlap(x0, x1, h, nx))
    return np.clip(cov / (h * h), 0, 1)


def _sized(region, d, dbu):
    return region.sized(int(round(d / dbu)))


# ---------------------------------------------------------------------------------------- silicon

def depletion(c0, m, pb, v):
    """The depletion approximation's width per unit capacitance: eps_Si / C(V), C = c0 / (1 + V / pb)^m."""
    return EPS_SI * (1 + max(v, 0.0) / pb) ** m / c0


def bias(design, net: str) -> float:
    """The reverse bias a junction of ``net`` holds while light is collected (V): the photodiodes and
    their EC / TG diffusions at the PD reset level, the storage node (FD) and the RST drain at the FD
    reset level, the supply's wells at the supply, any other node at half the supply."""
    px, sup = design.pixel, design.tech.supply
    if net.endswith(".pd") or net == "vpdr":
        return px.v_pd_reset
    if net.endswith(".fd") or net == "vrst":
        return px.v_fd_reset
    if net == "vdd":
        return sup
    return sup / 2


@dataclass
class Silicon:
    grid: object               # physics.collection.Grid
    labels: np.ndarray
    n_type: np.ndarray
    nets: list                 # label k >= 1 -> nets[k - 1]
    substrate: object          # physics.collection.Substrate
    depletion: dict            # net -> (bottom width, sidewall width) (m)


def cell_size(geo, h: float, pad_y: bool = False) -> tuple:
    """(nx, ny) of the cell at spacing ``h``; the cell must be a whole number of steps (``pad_y``: a cell
    that does not repeat along y is padded up to one)."""
    x0, y0, x1, y1 = geo.bbox
    nx, ny = (x1 - x0) / h, (y1 - y0) / h
    if pad_y:
        ny = float(np.ceil(ny - 1e-6))
    if abs(nx - round(nx)) > 1e-6 or abs(ny - round(ny)) > 1e-6:
        raise ConfigError("design", "light.grid", f"{h * 1e6:g} um",
                          f"a spacing that divides the pixel cell ({(x1 - x0) * 1e6:g} x {(y1 - y0) * 1e6:g} um)")
    return int(round(nx)), int(round(ny))


def polar(kind: str, net: str) -> str:
    """The name of a junction's collection in the model: the net for an n-type junction (electrons from
    the substrate: N+ diffusions, wells), ``<net>:p+`` for a P+ diffusion in a well (holes: its current
    has the other sign)."""
    return f"{net}:p+" if kind == "psd" else net


def silicon(design, geo, h: float, depth: float, own=None, periodic=(True, True)) -> Silicon:
    """The labelled grid of the cell's silicon (``physics.collection``). ``own``: the junctions (names of
    :func:`polar`) whose collection is solved one by one (default: the photodiodes and storage nodes);
    the others collect together. ``periodic``: a side that does not repeat reflects (a cell at the
    array's edge: the column circuits, the AFEs)."""
    from ...physics import collection as pc
    c = require(design)
    pd, mos = design.tech.photodiode, design.tech.mos
    nx, ny = cell_size(geo, h, pad_y=not periodic[1])
    widths = {}
    deepest = c.well_depth
    for kind, nets in geo.junctions.items():
        for net in nets:
            if kind in ("pd_n", "well"):
                wb, ws = (depletion(pd.cj, pd.mj, pd.pb, bias(design, net)),
                          c.well_depth * depletion(pd.cjsw, pd.mjsw, pd.pbsw, bias(design, net)))
                deepest = max(deepest, c.well_depth + wb)
            elif kind in ("nsd", "psd"):
                wb, ws = (depletion(mos.cj, mos.mj, mos.pb, bias(design, net)),
                          c.diffusion_depth * depletion(mos.cjsw, mos.mjsw, mos.pbsw, bias(design, net)))
            else:
                continue
            widths[(kind, net)] = (wb, ws)
    z = _layers(min(depth, 0.9 * c.substrate_thickness), deepest)     # a thin epitaxial layer: the grid stops in it
    grid = pc.Grid(h, nx, ny, z, tuple(periodic))
    zc = 0.5 * (z[:-1] + z[1:])
    labels = np.zeros(grid.shape, int)
    n_type = np.zeros(grid.shape, bool)
    names = {polar(k, n) for k, nets in geo.junctions.items() if k in ("pd_n", "well", "nsd", "psd") for n in nets}
    own = sorted(n for n in names if (n.endswith(OWN) if own is None else n in own))
    ids = {n: i + 1 for i, n in enumerate(own)}
    rest = len(own) + 1
    dbu = geo.dbu
    shift = (geo.bbox[0], geo.bbox[1])

    def lat(region, grow=0.0):
        import klayout.db as kdb
        r = _sized(region, grow, dbu) if grow else region
        r = r.moved(kdb.Vector(-int(round(shift[0] / dbu)), -int(round(shift[1] / dbu))))
        return coverage(r, dbu, h, nx, ny) >= 0.5

    order = ("pd_n", "well", "nsd", "psd", "ptap")
    for kind in order:
        for net, reg in sorted(geo.junctions.get(kind, {}).items()):
            label = ids.get(polar(kind, net), rest)
            if kind in ("pd_n", "well"):
                wb, ws = widths[(kind, net)]
                shell = lat(reg, ws)[None] & (zc < c.well_depth + wb)[:, None, None]
                inner = lat(reg, -h)[None] & (z[1:] <= c.well_depth - min(0.1e-6, c.well_depth / 4))[:, None, None]
                labels[shell & ~inner] = label
                n_type |= inner
            elif kind in ("nsd", "psd"):
                wb, ws = widths[(kind, net)]
                region = lat(reg, ws)[None] & (zc < c.diffusion_depth + wb)[:, None, None]
                labels[region] = label
                n_type &= ~region
            else:                                              # a substrate tap: carriers recombine there
                region = lat(reg)[None] & (zc < c.diffusion_depth)[:, None, None]
                labels[region] = -1
                n_type &= ~region
    n_type &= labels == 0
    sub = pc.Substrate(pc.Carriers(c.electron_diffusivity, c.electron_diffusion_length),
                       pc.Carriers(c.hole_diffusivity, c.hole_diffusion_length),
                       c.surface_recombination, c.substrate_thickness, _bottom(c))
    nets = own + [REST]
    return Silicon(grid, labels, n_type, nets, sub,
                   {f"{k}:{n}": (float(w[0]), float(w[1])) for (k, n), w in sorted(widths.items())})


def _bottom(c):
    return "recombining" if c.substrate_bottom == "recombining" else "reflecting"


def _layers(depth, junctions):
    """Layers 50 nm thick at the surface growing 20 % a layer through the junctions' depletion
    regions, then 25 % a layer down to ``depth``."""
    z = [0.0]
    step = 0.05e-6
    while z[-1] < junctions + 0.5e-6:
        z.append(z[-1] + step)
        step = min(step * 1.2, 0.5e-6)
    while z[-1] < depth * (1 - 1e-9):
        step *= 1.25
        z.append(min(z[-1] + step, depth) if depth - z[-1] > 1.5 * step else depth)
    return np.array(z)


# ---------------------------------------------------------------------------------------- optics

def heights(design) -> dict:
    """{metal: (z bottom, thickness)} from the ``[stack]`` or ``[collection.metals]``."""
    st = design.tech.stack
    if st is not None:
        return {c.name: (c.z, c.thickness) for c in st.conductors if c.name.startswith("metal")}
    return {m.name: (m.z, m.thickness) for m in require(design).metals}


def openings(geo, design) -> list:
    """Rectangles (x0, y0, a, b) in the cell's coordinates of the shield's openings small enough for the
    modal method, and the open region (KLayout) of the rest."""
    import klayout.db as kdb
    shield = _shield_name(design)
    dbu = geo.dbu
    x0, y0, x1, y1 = geo.bbox
    cell = kdb.Region(kdb.Box(*(int(round(v / dbu)) for v in geo.bbox)))
    metal = kdb.Region()
    for reg in geo.wires.get(shield, {}).values():
        metal += reg
    open_ = (cell - metal).merged()
    small = []
    for poly in open_.each():
        b = poly.bbox()
        a, bb = b.width() * dbu, b.height() * dbu
        if poly.is_box() and max(a, bb) <= MODAL_MAX:
            small.append((b.left * dbu - x0, b.bottom * dbu - y0, a, bb))
    return sorted(small)


def _shield_name(design) -> str:
    return design.tech.layout.aliases.get("shield", "metal5")


def optics(design, geo, h: float, secondary: tuple | None = None, light: str = "all", pad_y: bool = False,
           ny: int | None = None):
    """``physics.lightfield.Optics`` of the cell at spacing ``h``. ``secondary``: the small openings
    resized to this side (m) about their centres (the sizing's table); ``light``: ``all`` openings,
    ``small`` (the mask openings only: the secondary's own light), ``large`` (the primary's only) or
    ``full`` (a top metal over everything but the photodiodes' openings: the light map's full shield)."""
    from ...physics import lightfield as lf
    c = require(design)
    nx, n_y = cell_size(geo, h, pad_y)
    ny = ny or n_y                     # a padded cell: as many rows as the collection grid's times its ratio
    dbu = geo.dbu
    import klayout.db as kdb
    move = kdb.Vector(-int(round(geo.bbox[0] / dbu)), -int(round(geo.bbox[1] / dbu)))
    hs = heights(design)
    shield = _shield_name(design)
    if shield not in hs:
        raise ConfigError(design.tech.source, f"collection.metals.{shield}", MISSING,
                          f"the height of the shield's metal ({shield})")
    metal = kdb.Region()
    for reg in geo.wires.get(shield, {}).values():
        metal += reg
    covered = coverage(metal.moved(move), dbu, h, nx, ny) >= 0.5
    small = openings(geo, design)
    x = (np.arange(nx) + 0.5) * h
    y = (np.arange(ny) + 0.5) * h
    X, Y = np.meshgrid(x, y)
    modal = []
    for (ox, oy, a, b) in small:
        inside = (X > ox) & (X < ox + a) & (Y > oy) & (Y < oy + b)
        covered[inside] = True                                 # closed; reopened below as drawn or resized
        if light == "large":
            continue
        if secondary is not None:
            cx, cy = ox + a / 2, oy + b / 2
            ox, oy, a, b = cx - secondary / 2, cy - secondary / 2, secondary, secondary
        modal.append(lf.Opening(ox, oy, a, b))
        covered[(X > ox) & (X < ox + a) & (Y > oy) & (Y < oy + b)] = False
    if light == "small":
        covered[:] = True
        for op in modal:
            covered[(X > op.x0) & (X < op.x0 + op.a) & (Y > op.y0) & (Y < op.y0 + op.b)] = False
    if light == "full":                                        # only the photodiodes' openings stay open
        wells = kdb.Region()
        for reg in geo.junctions.get("pd_n", {}).values():
            wells += reg
        covered |= ~(coverage(wells.moved(move), dbu, h, nx, ny) >= 0.5)
    planes = []
    for name, (z, t) in sorted(hs.items(), key=lambda kv: kv[1][0]):
        if name == shield:
            continue
        reg = kdb.Region()
        for r in geo.wires.get(name, {}).values():
            reg += r
        m = coverage(reg.moved(move), dbu, h, nx, ny) >= 0.5
        if m.any():
            planes.append((z + t / 2, m))
    z_s, t_s = hs[shield]
    return lf.Optics(h, nx, ny, c.dielectric_index, z_s, t_s, covered, tuple(modal), tuple(planes))


# ---------------------------------------------------------------------------------------- response

@dataclass
class Response:
    """Per wavelength (``wavelength_m``) and net, electrons collected per photon incident on the cell."""
    wavelength_m: np.ndarray
    cell_area_m2: float
    eta: dict                                   # net -> array
    into_silicon: np.ndarray                    # fraction of the cell's light that entered the silicon
    opening_transmission: np.ndarray            # the mask openings' transmitted over geometric power (mean)
    opening_area_m2: float                      # one mask opening's drawn area
    depletion: dict = field(default_factory=dict)
    light: str = "all"

    def to_json(self) -> str:
        return json.dumps({"wavelength_m": self.wavelength_m.tolist(), "cell_area_m2": self.cell_area_m2,
                           "eta": {k: np.asarray(v).tolist() for k, v in self.eta.items()},
                           "into_silicon": self.into_silicon.tolist(),
                           "opening_transmission": self.opening_transmission.tolist(),
                           "opening_area_m2": self.opening_area_m2, "depletion": self.depletion, "light": self.light})

    @classmethod
    def from_json(cls, text: str) -> "Response":
        d = json.loads(text)
        return cls(np.array(d["wavelength_m"]), d["cell_area_m2"], {k: np.array(v) for k, v in d["eta"].items()},
                   np.array(d["into_silicon"]), np.array(d["opening_transmission"]), d["opening_area_m2"],
                   d["depletion"], d["light"])


def ratio(h: float, n: float, wavelength: float) -> int:
    """How many light-field points per collection step: the light field's grid must carry every plane
    wave that propagates in the dielectric (pi / h_light > 2 pi n / lambda, 2 % to spare)."""
    return max(1, int(np.ceil(1.02 * 2 * n * h / wavelength)))


def wavelengths(design, step: float | None = None) -> np.ndarray:
    lt = design.light
    step = step or lt.wavelength_step
    n = int(np.floor((lt.wavelength_max - lt.wavelength_min) / step + 1e-9)) + 1
    return lt.wavelength_min + step * np.arange(n)


def _code_hash(files=_CODE) -> str:
    root = Path(__file__).resolve().parents[2]
    h = hashlib.sha256()
    for rel in files:
        h.update(rel.encode())
        h.update((root / rel).read_bytes())
    return h.hexdigest()


def _digest(*parts) -> str:
    """SHA-256 of ``parts``: arrays by their bytes (never their repr, which numpy abbreviates), tuples and
    lists item by item, anything else by its repr."""
    h = hashlib.sha256()

    def feed(p):
        if isinstance(p, np.ndarray):
            h.update(f"array{p.shape}{p.dtype}".encode())
            h.update(np.ascontiguousarray(p).tobytes())
        elif isinstance(p, (tuple, list)):
            h.update(f"seq{len(p)}(".encode())
            for x in p:
                feed(x)
            h.update(b")")
        else:
            h.update(repr(p).encode())
    for p in parts:
        feed(p)
    return h.hexdigest()


def _store():
    from ...cachestore import Store
    return Store("light", "report-cache", "computing it again")


_MAPS: dict = {}


def maps(sil: Silicon):
    """The collection maps of ``sil`` (``physics.collection.solve``), cached by its geometry and parameters."""
    from ...physics import collection as pc
    key = _digest("maps", _code_hash(_MAPS_CODE), sil.grid.periodic, sil.grid.h, sil.grid.nx, sil.grid.ny, sil.grid.z, sil.labels, sil.n_type,
                  sil.substrate)
    if key in _MAPS:
        return _MAPS[key]
    files = _store().load(key)
    if files:
        z = np.load(io.BytesIO(files["maps.npz"]))
        m = pc.Maps(sil.grid, sil.substrate, {int(k[4:]): z[k] for k in z.files if k.startswith("psi_")},
                    json.loads(files["bottom.json"].decode()))
        m.bottom = {int(k): v for k, v in m.bottom.items()}
    else:
        m = pc.solve(sil.grid, sil.labels, sil.n_type, sil.substrate)
        buf = io.BytesIO()
        np.savez_compressed(buf, **{f"psi_{k}": v for k, v in m.psi.items()})
        _store().save(key, {"maps.npz": buf.getvalue(), "bottom.json": json.dumps(m.bottom).encode()})
    _MAPS[key] = m
    return m


def response(design, geo=None, secondary: float | None = None, light: str = "all", say=None, own=None,
             periodic=(True, True), grid: float | None = None, step: float | None = None) -> Response:
    """The collection model of ``design``'s dual pixel (cached; ``geo``: its ``pixel_geometry`` when made),
    or of another cell ``geo`` (``own``, ``periodic``: as :func:`silicon`; ``grid``, ``step``: the lateral
    spacing and wavelength step instead of the design's). ``secondary``, ``light``: as :func:`optics`."""
    from ...physics import lightfield as lf, silicon as si
    lt = design.light
    h = grid or lt.grid
    geo = geo if geo is not None else pixel_geometry(design)
    sil = silicon(design, geo, h, lt.depth, own, periodic)
    wl = wavelengths(design, step)
    n_ox = require(design).dielectric_index
    need = {float(w): ratio(h, n_ox, w) for w in wl}
    opt = {r: optics(design, geo, h / r, secondary, light, not periodic[1], sil.grid.ny * r)
           for r in sorted(set(need.values()))}
    key = _digest("response", _code_hash(), sil.grid.h, sil.grid.periodic, sil.nets, sil.grid.z, sil.labels,
                  sil.n_type, sil.substrate,
                  wl, design.temperature, *[(o.shield, o.modal, o.metals, o.shield_z, o.shield_thickness,
                                             o.n_dielectric) for o in opt.values()])
    files = _store().load(key)
    if files:
        return Response.from_json(files["response.json"].decode())
    if say:
        say(f"collection model of {geo.top}: {len(sil.nets)} collection maps, {wl.size} wavelengths")
    m = maps(sil)
    eta = {n: np.zeros(wl.size) for n in sil.nets}
    into = np.zeros(wl.size)
    trans = np.zeros(wl.size)
    for i, w in enumerate(wl):
        r = need[float(w)]
        ab = lf.absorbed(opt[r], float(w), complex(si.index(w, design.temperature)),
                         float(si.alpha(w, design.temperature)), sil.grid.z, r)
        col = m.collected(ab.voxels, ab.deep)
        for k, n in enumerate(sil.nets):
            eta[n][i] = col.get(k + 1, 0.0)
        into[i] = ab.into_silicon
        trans[i] = float(np.mean(list(ab.opening_transmission.values()))) if ab.opening_transmission else np.nan
        if say:
            say(f"collection model: {w * 1e9:.0f} nm")
    small = openings(geo, design)
    area = (secondary ** 2 if secondary is not None else small[0][2] * small[0][3]) if small else 0.0
    out = Response(wl, float(sil.grid.h ** 2 * sil.grid.nx * sil.grid.ny), eta, into, trans, area,
                   sil.depletion, light)
    _store().save(key, {"response.json": out.to_json().encode()})
    return out
