"""The light field under the layout's metals, and the carriers it generates in the silicon.

A pixel cell (periodic: an array of identical cells) is lit from above by a plane wave in the
dielectric over the top-metal shield. What leaves the shield's openings is, per opening:

- a small rectangular opening (``Opening.modal``, the mask opening of a masked subpixel): the
  modal solution of the thick perfectly conducting screen (``aperture``), the waveguide modes'
  field at the exit face, taken onto the cell's plane-wave orders exactly (closed-form overlaps);
- a large one (the primary's photodiode): the incident field over the opening (Kirchhoff), exact
  to O(lambda / width).

Below the shield, every transverse field component obeys the Helmholtz equation of the
homogeneous dielectric, so each plane-wave order propagates by exp(i k_z dz) (the angular
spectrum [Goodman2005] ch. 3.10; evanescent orders decay). The lower metals are opaque planes at
their heights (a mirror, E_t -> -E_t, where drawn: Kirchhoff boundary conditions, [Goodman2005]
ch. 3.4); the silicon surface reflects and transmits each order by the Fresnel coefficients of
its polarisation and angle (the transverse-field form t = 2 Y_1 / (Y_1 + Y_2)). Light reflected
by the silicon goes back up, is reflected again by the metals' undersides (the shield's too) or
leaves through the openings: this is the light guided under the shield. Its successive
arrivals at the silicon are added as intensities (the round trips are several microns, longer
than the coherence length of a broadband source, lambda^2 / d lambda ~ 1 - 3 um).

In the silicon (complex index from ``silicon``) each order continues with its own k_z; the
absorbed power density is alpha n_Si |E|^2 / Re(Y_incident) of the normalised field (with
E_z = -(k_t . E_t) / k_z): per voxel of the collection grid, the first arrival is resolved in
depth (the interference of the orders at each layer's top, decaying within the layer as
exp(-alpha dz)); later arrivals, weaker and diffuse, decay from their surface pattern. Below the
grid only the lateral mean matters (the collection there is laterally uniform).

Units: everything per incident photon on the cell (the incident power over the cell is 1): the
returned generation is the fraction of the cell's photons absorbed in each voxel.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.fft as fft

from . import aperture as ap


@dataclass(frozen=True)
class Opening:
    """A rectangular opening of the shield (m, the cell's coordinates) solved by the modal method."""
    x0: float
    y0: float
    a: float
    b: float


@dataclass(frozen=True)
class Optics:
    """The cell's optical description on a periodic grid of spacing ``h`` (``nx`` x ``ny`` points)."""
    h: float
    nx: int
    ny: int
    n_dielectric: float
    shield_z: float                 # height of the shield's underside above the silicon (m)
    shield_thickness: float
    shield: np.ndarray              # bool (ny, nx): top metal present
    modal: tuple = ()               # Opening, each also open in ``shield``
    metals: tuple = ()              # ((z, bool (ny, nx) mask), ...) the lower metals, any order
    lattice: float = 4e-6           # period of the lattice each modal opening is solved in
    bounces: int = 8                # at most this many arrivals at the silicon
    floor: float = 5e-3             # stop when the light left under the shield is below this share of what entered

    @property
    def area(self) -> float:
        return self.h * self.h * self.nx * self.ny


@dataclass
class Absorbed:
    """Per incident photon on the cell: absorbed fraction in each voxel (``voxels``, the collection
    grid's shape), the laterally integrated fraction per metre below the grid (``deep(z)``), and the
    light's bookkeeping."""
    voxels: np.ndarray
    deep_density: float             # absorbed fraction per metre at the grid's bottom, laterally summed
    alpha: float
    z_bottom: float
    into_silicon: float             # fraction of the cell's light that entered the silicon
    opening_transmission: dict = field(default_factory=dict)   # Opening -> transmitted / geometric power

    def deep(self, z):
        return self.deep_density * np.exp(-self.alpha * (np.asarray(z) - self.z_bottom))


def _orders(o: Optics, kt):
    """The cell's orders kt + G: 1D kx (nx), ky (ny), and their (ny, nx) mesh."""
    kx1 = kt[0] + 2 * np.pi * fft.fftfreq(o.nx, o.h)
    ky1 = kt[1] + 2 * np.pi * fft.fftfreq(o.ny, o.h)
    kx, ky = np.meshgrid(kx1, ky1)
    return kx1, ky1, kx, ky


class _Basis:
    """Per order: the s and p unit vectors and the dielectric's admittances (power of a spectrum)."""

    def __init__(self, kx, ky, eps, k0):
        es, ep = ap.polarisations(kx.ravel(), ky.ravel())
        self.es = es.reshape(2, *kx.shape)
        self.ep = ep.reshape(2, *kx.shape)
        ys, yp = ap.admittances(eps, k0, kx, ky)
        self.ys, self.yp = ys, yp
        self.ws, self.wp = ys.real, yp.real

    def sp(self, ex, ey):
        return ex * self.es[0] + ey * self.es[1], ex * self.ep[0] + ey * self.ep[1]

    def xy(self, ts, tp):
        return ts * self.es[0] + tp * self.ep[0], ts * self.es[1] + tp * self.ep[1]

    def power(self, ex, ey):
        ts, tp = self.sp(ex, ey)
        return float(np.sum(self.ws * np.abs(ts) ** 2 + self.wp * np.abs(tp) ** 2))


def exit_field(o: Optics, k0: float, kt, polarisations) -> tuple:
    """For each incident transverse polarisation (|E| = 1): the spectra (Ex, Ey), shape (ny, nx) on the
    orders of ``_orders``, of the field leaving the shield's underside; and each modal opening's
    transmitted power over the power incident on its drawn area."""
    eps = o.n_dielectric ** 2
    kx1, ky1, _kx, _ky = _orders(o, kt)
    x = (np.arange(o.nx) + 0.5) * o.h
    y = (np.arange(o.ny) + 0.5) * o.h
    X, Y = np.meshgrid(x, y)
    kirch = ~o.shield
    for op in o.modal:
        kirch &= ~((X > op.x0) & (X < op.x0 + op.a) & (Y > op.y0) & (Y < op.y0 + op.b))
    # over a Kirchhoff opening the field is exp(i kt.r) e_inc: c_G = mean(mask exp(-i G.r)) e_inc
    mask = fft.fft2(kirch) / (o.nx * o.ny)
    out = [[mask * e[0], mask * e[1]] for e in polarisations]
    trans = {}
    solved = {}
    for op in o.modal:
        shape = (round(op.a / o.h * 64), round(op.b / o.h * 64))
        if shape not in solved:                 # identical openings: one solution
            solved[shape] = local_solution(o, op, k0, kt, polarisations)
        P, sols = solved[shape]
        trans[op] = float(np.mean([s.transmittance for s in sols]) * P * P / (op.a * op.b))
        md = ap.rect_modes(op.x0, op.y0, op.a, op.b, eps, k0, _kc(op, eps, k0))
        for j, sol in enumerate(sols):
            # the local solution is for an incident field of amplitude 1 / sqrt(P^2): scale to amplitude 1
            sx, sy = md.spectrum(sol.bottom * P, kx1, ky1, o.area)
            out[j][0] = out[j][0] + sx
            out[j][1] = out[j][1] + sy
    return out, trans


def local_solution(o: Optics, op: Opening, k0: float, kt, polarisations) -> tuple:
    """(P, solutions): the modal solution of opening ``op`` alone in a P x P lattice (P = ``o.lattice``,
    at least twice the opening), one per incident polarisation."""
    eps = o.n_dielectric ** 2
    P = max(o.lattice, 2 * max(op.a, op.b))
    kc = _kc(op, eps, k0)
    lat = ap.Lattice(P, P, eps, k0, kc + 4 * np.pi / min(op.a, op.b), tuple(kt))
    md = ap.rect_modes((P - op.a) / 2, (P - op.b) / 2, op.a, op.b, eps, k0, kc)
    return P, ap.solve_screen(lat, [md], o.shield_thickness, list(polarisations))


def transmission(o: Optics, op: Opening, wavelength: float, kt=(0.0, 0.0), modal_max: float = 3e-6) -> float:
    """Power the opening passes over the power incident on its drawn area, unpolarised light (1 for an
    opening wider than ``modal_max``: geometric, as the light field treats it)."""
    if min(op.a, op.b) > modal_max:
        return 1.0
    k0 = 2 * np.pi / wavelength
    es, ep = ap.polarisations(np.array([kt[0]]), np.array([kt[1]]))
    P, sols = local_solution(o, op, k0, kt, [(es[0, 0], es[1, 0]), (ep[0, 0], ep[1, 0])])
    return float(np.mean([s.transmittance for s in sols]) * P * P / (op.a * op.b))


def _kc(op: Opening, eps, k0):
    """The modes' cutoff: every propagating mode and the evanescent ones up to 2 pi / width beyond."""
    return np.sqrt(eps) * k0 + 2 * np.pi / min(op.a, op.b)


def absorbed(o: Optics, wavelength: float, n_si: complex, alpha: float, grid_z: np.ndarray, ratio: int,
             kt=(0.0, 0.0)) -> Absorbed:
    """Absorbed fraction of the cell's photons in each voxel of the collection grid (lateral spacing
    ``ratio`` x ``o.h``, layers ``grid_z``), unpolarised light (the mean of the s and p polarisations)
    incident with transverse wavevector ``kt``."""
    k0 = 2 * np.pi / wavelength
    eps = o.n_dielectric ** 2
    eps_si = n_si ** 2
    kx1, ky1, kx, ky = _orders(o, kt)
    base = _Basis(kx, ky, eps, k0)
    kz = ap.kz_of(eps, k0, kx, ky)
    kz_si = np.sqrt(eps_si * k0 ** 2 - kx ** 2 - ky ** 2 + 0j)
    kz_si = np.where(kz_si.imag < 0, -kz_si, kz_si)
    ys_s, yp_s = kz_si / k0, eps_si * k0 / kz_si
    fresnel = ((base.ys - ys_s) / (base.ys + ys_s), (base.yp - yp_s) / (base.yp + yp_s))
    y_inc = ap.admittances(eps, k0, np.array([kt[0]]), np.array([kt[1]]))
    es, ep = ap.polarisations(np.array([kt[0]]), np.array([kt[1]]))
    pols = [(es[0, 0], es[1, 0]), (ep[0, 0], ep[1, 0])]
    p_inc = [float(y_inc[0].real[0]), float(y_inc[1].real[0])]
    nz, ny, nx = len(grid_z) - 1, o.ny // ratio, o.nx // ratio
    vox = np.zeros((nz, ny, nx))
    dz = np.diff(grid_z)
    within = -np.expm1(-alpha * dz) / alpha            # integral of exp(-alpha (z - z_top)) over each layer
    deep = 0.0
    into = 0.0
    fields, trans = exit_field(o, k0, kt, pols)
    planes = sorted(o.metals, key=lambda p: p[0])
    npts = o.nx * o.ny
    for (ex, ey), pin in zip(fields, p_inc):
        for i, (ts, tp) in enumerate(_bounce(o, ex, ey, kz, base, planes, fresnel, pin)):
            sx, sy = base.xy(ts, tp)
            sz = -(kx * sx + ky * sy) / kz_si
            into += float(np.sum(ys_s.real * np.abs(ts) ** 2 + yp_s.real * np.abs(tp) ** 2)) / pin / 2
            scale = alpha * n_si.real / pin / npts / 2            # absorbed per point, per unit depth
            if i == 0:                                            # resolved in depth
                dens = np.empty((nz, o.ny, o.nx))
                for l, d in enumerate(grid_z[:-1]):
                    ph = np.exp(1j * kz_si * d)
                    dens[l] = sum(np.abs(fft.ifft2((c * ph).astype(SPECTRUM)) * npts) ** 2 for c in (sx, sy, sz)) * scale
            else:                                                 # its surface pattern, decaying
                top = sum(np.abs(fft.ifft2(c.astype(SPECTRUM)) * npts) ** 2 for c in (sx, sy, sz)) * scale
                dens = top[None] * np.exp(-alpha * grid_z[:-1])[:, None, None]
            vox += (dens * within[:, None, None]).reshape(nz, ny, ratio, nx, ratio).sum(axis=(2, 4))
            deep += float(dens[-1].sum()) * np.exp(-alpha * dz[-1])
    return Absorbed(vox, deep, alpha, float(grid_z[-1]), into, trans)


def _bounce(o, ex, ey, kz, base, planes, fresnel, p_inc):
    """The field's successive arrivals at the silicon (s, p spectra of E_t just inside it): the lower
    metals reflect both ways where drawn, the shield's underside reflects, its openings let light out."""
    p_exit = base.power(ex, ey)
    zs = [0.0] + [p[0] for p in planes] + [o.shield_z]
    masks = [None] + [p[1] for p in planes] + [o.shield]
    n = len(zs)
    prop = [np.exp(1j * kz * (zs[i + 1] - zs[i])).astype(SPECTRUM) for i in range(n - 1)]
    none = None
    down = [none] * n
    up = [none] * n
    down[-1] = (ex.astype(SPECTRUM), ey.astype(SPECTRUM))
    out = []
    r_s, r_p = (r.astype(SPECTRUM) for r in fresnel)
    for _step in range(o.bounces * n):
        arr_down = [none] * n
        arr_up = [none] * n
        for i in range(n - 1):
            if down[i + 1] is not None:
                arr_down[i] = (down[i + 1][0] * prop[i], down[i + 1][1] * prop[i])
            if up[i] is not None:
                arr_up[i + 1] = (up[i][0] * prop[i], up[i][1] * prop[i])
        down = [none] * n
        up = [none] * n
        if arr_down[0] is not None:
            ts, tp = base.sp(*arr_down[0])
            out.append((ts * (1 + r_s), tp * (1 + r_p)))
            up[0] = tuple(c.astype(SPECTRUM) for c in base.xy(ts * r_s, tp * r_p))
        for i in range(1, n):
            down[i], up[i] = _plane(arr_down[i], arr_up[i], masks[i], top=i == n - 1)
        left = sum(base.power(*f) for f in down + up if f is not None)
        if len(out) >= o.bounces or left < o.floor * p_exit:
            break
    return out


#: the spectra's precision in the bounces: single (the FFTs are nearly all of the light field's cost; their
#: rounding, ~1e-7 of the field, is far below the model's other errors: benchmarks/light_map.py measures it)
SPECTRUM = np.complex64


def _plane(ad, au, mask, top=False):
    """(down, up) spectra leaving a metal plane that ``ad`` (going down) and ``au`` (going up) arrive at: where
    the metal is drawn (``mask``) each is reflected (E_t -> -E_t) into the other direction, elsewhere it passes;
    the shield (``top``) lets the light going up out through its openings. One inverse transform per arriving
    field and one transform per leaving one; a plane all metal or all open needs none (None: no field)."""
    if not mask.any():
        return (None, None) if top else (ad, au)
    if mask.all():
        return _neg(au), (None if top else _neg(ad))
    rd, ru = _real(ad), _real(au)
    if top:
        return _spectrum(_sub(None, ru, mask)), None
    return _spectrum(_sub(_keep(rd, ~mask), ru, mask)), _spectrum(_sub(_keep(ru, ~mask), rd, mask))


def _real(f):
    return None if f is None else tuple(fft.ifft2(c) for c in f)


def _spectrum(f):
    return None if f is None else tuple(fft.fft2(c) for c in f)


def _neg(f):
    return None if f is None else (-f[0], -f[1])


def _keep(f, mask):
    return None if f is None else (f[0] * mask, f[1] * mask)


def _sub(a, b, mask):
    """a - b x mask (fields in real space; None: no field)."""
    if b is None:
        return a
    mb = (b[0] * mask, b[1] * mask)
    return (-mb[0], -mb[1]) if a is None else (a[0] - mb[0], a[1] - mb[1])
