"""Light through an opening in the top-metal shield: the modal method for a hole in a thick metal screen.

A mask opening of the secondary is 0.6 - 0.8 um wide in a 1.2 um thick top metal, 0.7 - 1.9
wavelengths in the oxide: neither geometric optics (which passes the drawn area) nor Bethe's
small-hole limit (a hole much smaller than the wavelength in an infinitely thin screen, whose
transmission falls as (k a)^4 [Bethe1944]) describes it. The kit solves it as what it is, a
short metal waveguide between two dielectric half-spaces, by the modal method
([MartinMoreno2001], [GarciaVidal2010] sec. II): above and below the screen the field is a sum
of plane-wave orders of a lattice (the openings repeat with the pixels, so the lattice is real;
``Lattice``), inside each opening a sum of the waveguide modes of a perfectly conducting
rectangular guide (``rect_modes``: TE_mn and TM_mn, propagating and evanescent) or of a slit
(``slit_modes``, the 2D case the published checks use). The tangential E and H are matched on
the two faces: with E_a, E'_a the modes' transverse-E amplitudes at the top and bottom faces,

    sum_b G_ab E_b + i Y_a cot(beta_a t) E_a - i Y_a csc(beta_a t) E'_a = 2 sum_s a_s Y_0s <a|0s>
    sum_b G_ab E'_b + i Y_a cot(beta_a t) E'_a - i Y_a csc(beta_a t) E_a = 0,
    G_ab = sum_(k,s) Y_ks <a|ks> <ks|b>,

where <ks|a> is the overlap of mode a with order k in polarisation s (s or p), Y their admittances
(in units of the vacuum's: k_z / k0 for s, eps k0 / k_z for p; beta / k0 for TE modes,
eps k0 / beta for TM) and a_s the incident amplitudes. The transmitted orders are
t_ks = sum_a <ks|a> E'_a. The overlaps are closed forms (products of 1D integrals of sines and
cosines with a plane wave), the sums run over every order up to ``kmax``.

Limits, said where the numbers are used (docs/light-collection.md): the metal is a perfect
conductor (aluminium's ~10 nm skin depth widens an opening by ~2 % and absorbs a little; not
counted); an opening is a rectangle (a drawn non-rectangular opening is treated geometrically by
the light field, ``lightfield``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Lattice:
    """Plane-wave orders of a rectangular lattice of periods ``px``, ``py`` (m) in a dielectric of
    relative permittivity ``eps``, at vacuum wavenumber ``k0``, for an incident transverse wavevector
    ``kt`` (oblique light), up to |k| < ``kmax``."""
    px: float
    py: float
    eps: float
    k0: float
    kmax: float
    kt: tuple = (0.0, 0.0)

    def orders(self):
        """kx, ky (1D arrays, one entry per order; the incident order first)."""
        ni, nj = int(self.kmax * self.px / (2 * np.pi)) + 1, int(self.kmax * self.py / (2 * np.pi)) + 1
        i, j = np.meshgrid(np.arange(-ni, ni + 1), np.arange(-nj, nj + 1), indexing="ij")
        kx = self.kt[0] + 2 * np.pi * i.ravel() / self.px
        ky = self.kt[1] + 2 * np.pi * j.ravel() / self.py
        keep = np.hypot(kx - self.kt[0], ky - self.kt[1]) < self.kmax
        kx, ky = kx[keep], ky[keep]
        first = np.argmin(np.abs(kx - self.kt[0]) + np.abs(ky - self.kt[1]))
        order = np.r_[first, np.delete(np.arange(kx.size), first)]
        return kx[order], ky[order]


def polarisations(kx, ky):
    """Unit transverse vectors (es, ep), each (2, n): s = z x k_t / |k_t|, p = k_t / |k_t|; at k_t = 0,
    p = x and s = y."""
    kt = np.hypot(kx, ky)
    zero = kt < 1e-9 * (np.max(kt) + 1.0)
    ktn = np.where(zero, 1.0, kt)
    ep = np.where(zero, [[1.0], [0.0]], np.vstack([kx, ky]) / ktn)
    es = np.where(zero, [[0.0], [1.0]], np.vstack([-ky, kx]) / ktn)
    return es, ep


def kz_of(eps, k0, kx, ky):
    """k_z with Im >= 0 (decaying away from the screen), kept off zero at a grazing order."""
    kz = np.sqrt(eps * k0 ** 2 - kx ** 2 - ky ** 2 + 0j)
    return np.where(np.abs(kz) < 1e-9 * k0, 1e-9 * k0, kz)


def admittances(eps, k0, kx, ky):
    """(Y_s, Y_p) of each order, in units of the vacuum's admittance."""
    kz = kz_of(eps, k0, kx, ky)
    return kz / k0, eps * k0 / kz


def _f(u, a):
    """integral_0^a exp(i u x) dx (u array)."""
    u = np.asarray(u, complex)
    small = np.abs(u * a) < 1e-8
    return np.where(small, a + 0.5j * u * a * a, (np.exp(1j * u * a) - 1) / np.where(small, 1.0, 1j * u))


def _cos(m, a, q):
    """integral_0^a cos(m pi x / a) exp(-i q x) dx, m (n_modes,) x q (n_orders,) -> (n_orders, n_modes)."""
    p = np.pi * np.asarray(m)[None, :] / a
    q = np.asarray(q)[:, None]
    return 0.5 * (_f(p - q, a) + _f(-p - q, a))


def _sin(m, a, q):
    p = np.pi * np.asarray(m)[None, :] / a
    q = np.asarray(q)[:, None]
    return (_f(p - q, a) - _f(-p - q, a)) / 2j


@dataclass(frozen=True)
class Modes:
    """Waveguide modes of one opening: cutoff, propagation constant, admittance, and how to take
    their overlaps with plane-wave orders."""
    kind: str                 # "rect" or "slit"
    x0: float                 # the opening's lower-left corner (m)
    y0: float
    a: float                  # width (x)
    b: float                  # height (y); a slit: the period it spans
    te: np.ndarray            # True: TE mode, False: TM (TEM of a slit: TM, m = 0)
    m: np.ndarray
    n: np.ndarray
    beta: np.ndarray
    y: np.ndarray             # admittance

    def overlaps(self, kx, ky, area: float) -> np.ndarray:
        """<k s|a>: (2 n_orders, n_modes), s-polarisation rows first, then p (plane waves normalised over
        ``area``, the lattice cell)."""
        es, ep = polarisations(kx, ky)
        ex, ey = self._projections(kx, ky)
        shift = np.exp(-1j * (kx * self.x0 + ky * self.y0))[:, None] / np.sqrt(area)
        s = (es[0][:, None] * ex + es[1][:, None] * ey) * shift
        p = (ep[0][:, None] * ex + ep[1][:, None] * ey) * shift
        return np.vstack([s, p])

    def _projections(self, kx, ky):
        """Integrals of the modes' x and y components times exp(-i k.r) over the opening, (n_orders, n_modes)."""
        a, b, m, n, te = self.a, self.b, self.m, self.n, self.te
        if self.kind == "slit":                     # uniform along y over the period: only ky = 0 couples
            on = np.isclose(ky, 0.0, atol=1e-6 * np.pi / b)[:, None] * b
            norm = np.where(m == 0, np.sqrt(1.0 / (a * b)), np.sqrt(2.0 / (a * b)))
            ex = np.where(~te, _cos(m, a, kx), 0) * on * norm       # TM_m: E_x = cos(m pi x / a)
            ey = np.where(te, _sin(m, a, kx), 0) * on * norm        # TE_m: E_y = sin(m pi x / a)
            return ex, ey
        cx, sx, cy, sy = _cos(m, a, kx), _sin(m, a, kx), _cos(n, b, ky), _sin(n, b, ky)
        fx = np.where(te, n / b, m / a)             # E_x = fx cos(m pi x / a) sin(n pi y / b)
        fy = np.where(te, -m / a, n / b)            # E_y = fy sin(m pi x / a) cos(n pi y / b)
        ca, sa = np.where(m == 0, a, a / 2), np.where(m == 0, 0.0, a / 2)
        cb, sb = np.where(n == 0, b, b / 2), np.where(n == 0, 0.0, b / 2)
        norm = 1.0 / np.sqrt(fx ** 2 * ca * sb + fy ** 2 * sa * cb)
        return fx * norm * cx * sy, fy * norm * sx * cy

    def spectrum(self, amplitudes, kx, ky, area: float):
        """(Ex, Ey) coefficients, shape (len(ky), len(kx)), of the field ``sum amplitudes_a mode_a`` on the
        plane waves exp(i (kx x + ky y)) of a cell of ``area`` (the field's mean times exp(-i k.r)): the
        overlaps of a rectangle separate into x and y integrals, so this is one matrix product per
        component."""
        if self.kind != "rect":
            raise ValueError("spectrum: rectangular openings only")
        a, b, m, n, te = self.a, self.b, self.m, self.n, self.te
        c = np.asarray(amplitudes)
        keep = np.abs(c) > 1e-9 * (np.abs(c).max() + 1e-300)
        c, m, n, te = c[keep], m[keep], n[keep], te[keep]
        fx = np.where(te, n / b, m / a)
        fy = np.where(te, -m / a, n / b)
        ca, sa = np.where(m == 0, a, a / 2), np.where(m == 0, 0.0, a / 2)
        cb, sb = np.where(n == 0, b, b / 2), np.where(n == 0, 0.0, b / 2)
        w = c / np.sqrt(fx ** 2 * ca * sb + fy ** 2 * sa * cb) / area
        kx, ky = np.asarray(kx), np.asarray(ky)
        px = np.exp(-1j * kx * self.x0)[:, None]
        py = np.exp(-1j * ky * self.y0)[:, None]
        cx, sx = _cos(m, a, kx) * px, _sin(m, a, kx) * px
        cy, sy = _cos(n, b, ky) * py, _sin(n, b, ky) * py
        return (sy * (w * fx)) @ cx.T, (cy * (w * fy)) @ sx.T

    def field(self, amplitudes, x, y):
        """Transverse E (Ex, Ey) of ``sum amplitudes_a mode_a`` at points ``x``, ``y`` (zero outside)."""
        xs, ys = np.asarray(x) - self.x0, np.asarray(y) - self.y0
        inside = (xs >= 0) & (xs <= self.a) & (ys >= 0) & (ys <= self.b)
        ex = np.zeros(np.shape(x), complex)
        ey = np.zeros(np.shape(x), complex)
        for c, te, m, n in zip(amplitudes, self.te, self.m, self.n):
            if self.kind == "slit":
                norm = np.sqrt((1.0 if m == 0 else 2.0) / (self.a * self.b))
                if te:
                    ey += c * norm * np.sin(m * np.pi * xs / self.a)
                else:
                    ex += c * norm * np.cos(m * np.pi * xs / self.a)
                continue
            a, b = self.a, self.b
            fx, fy = (n / b, -m / a) if te else (m / a, n / b)
            ca, sa = (a if m == 0 else a / 2), (0.0 if m == 0 else a / 2)
            cb, sb = (b if n == 0 else b / 2), (0.0 if n == 0 else b / 2)
            norm = 1.0 / np.sqrt(fx ** 2 * ca * sb + fy ** 2 * sa * cb)
            ex += c * norm * fx * np.cos(m * np.pi * xs / a) * np.sin(n * np.pi * ys / b)
            ey += c * norm * fy * np.sin(m * np.pi * xs / a) * np.cos(n * np.pi * ys / b)
        return np.where(inside, ex, 0), np.where(inside, ey, 0)


def _guided(kc, te, eps, k0):
    beta = np.sqrt(eps * k0 ** 2 - kc ** 2 + 0j)
    beta = np.where(np.abs(beta) < 1e-9 * k0, 1e-9 * k0, beta)
    return beta, np.where(te, beta / k0, eps * k0 / beta)


def rect_modes(x0, y0, a, b, eps, k0, kc_max) -> Modes:
    """TE_mn (m, n >= 0, not both 0) and TM_mn (m, n >= 1) of an a x b perfectly conducting guide filled
    with ``eps``, cutoff below ``kc_max``."""
    mm, nn = int(kc_max * a / np.pi) + 1, int(kc_max * b / np.pi) + 1
    m, n = np.meshgrid(np.arange(mm + 1), np.arange(nn + 1), indexing="ij")
    m, n = m.ravel(), n.ravel()
    kc = np.hypot(m * np.pi / a, n * np.pi / b)
    te_ok = (kc > 0) & (kc < kc_max)
    tm_ok = (m > 0) & (n > 0) & (kc < kc_max)
    te = np.r_[np.ones(te_ok.sum(), bool), np.zeros(tm_ok.sum(), bool)]
    m_, n_, kc_ = np.r_[m[te_ok], m[tm_ok]], np.r_[n[te_ok], n[tm_ok]], np.r_[kc[te_ok], kc[tm_ok]]
    beta, y = _guided(kc_, te, eps, k0)
    return Modes("rect", x0, y0, a, b, te, m_, n_, beta, y)


def slit_modes(x0, a, period_y, eps, k0, kc_max) -> Modes:
    """Modes of a slit of width ``a`` (x) uniform along y: TM_m (E_x = cos(m pi x / a), m >= 0; m = 0 is
    the TEM mode, never cut off) and TE_m (E_y = sin(m pi x / a), m >= 1)."""
    mm = int(kc_max * a / np.pi) + 1
    m = np.arange(mm + 1)
    te = np.r_[np.zeros(m.size, bool), np.ones(m.size - 1, bool)]
    m_ = np.r_[m, m[1:]]
    beta, y = _guided(m_ * np.pi / a, te, eps, k0)
    return Modes("slit", x0, 0.0, a, period_y, te, m_, np.zeros_like(m_), beta, y)


@dataclass
class Solution:
    top: np.ndarray           # E_a at the top face
    bottom: np.ndarray        # E'_a at the bottom face (what leaves the opening)
    transmitted: np.ndarray   # t_ks: (2 n_orders,) s rows then p
    reflected: np.ndarray     # r_ks (the incident order's specular part included, a lattice's only)
    power_in: float           # incident power over the lattice cell (per unit area x cell area)
    power_t: float            # transmitted power, same units
    power_r: float

    @property
    def transmittance(self) -> float:
        """Transmitted over incident power (a lattice: per cell; ``Orders`` of a continuum: a width or
        an area, the transmission cross-section)."""
        return self.power_t / self.power_in


@dataclass(frozen=True)
class Orders:
    """The plane waves the field outside the screen is summed over: a lattice's orders (``weight`` 1,
    overlaps normalised over the cell ``area``) or a quadrature of the continuum of an isolated
    opening (``weight`` dk / 2 pi, ``area`` 1)."""
    kx: np.ndarray
    ky: np.ndarray
    weight: np.ndarray
    eps: float
    k0: float
    area: float

    @classmethod
    def of(cls, lattice: Lattice) -> "Orders":
        kx, ky = lattice.orders()
        return cls(kx, ky, np.ones(kx.size), lattice.eps, lattice.k0, lattice.px * lattice.py)


def solve_screen(orders: Orders | Lattice, modes: list, thickness: float, e_inc, kt=(0.0, 0.0)):
    """Light of transverse polarisation ``e_inc`` (Ex, Ey), incident with transverse wavevector ``kt``
    (a lattice's own), through the openings ``modes`` (one ``Modes`` per opening, all in one cell) of a
    perfectly conducting screen of ``thickness``, the same dielectric above, in and below. A list of
    polarisations gives a list of solutions (one factorisation)."""
    many = isinstance(e_inc, list)
    sols = _solve(orders, modes, thickness, e_inc if many else [e_inc], kt)
    return sols if many else sols[0]


def _solve(orders, modes, thickness, polarisations_in, kt):
    if isinstance(orders, Lattice):
        kt, orders = orders.kt, Orders.of(orders)
    o = orders
    ys, yp = admittances(o.eps, o.k0, o.kx, o.ky)
    yk = np.r_[ys, yp]
    w = np.r_[o.weight, o.weight]
    O = np.hstack([md.overlaps(o.kx, o.ky, o.area) for md in modes])
    kix, kiy = np.array([kt[0]]), np.array([kt[1]])
    Oi = np.hstack([md.overlaps(kix, kiy, o.area) for md in modes])       # (2, n_modes): s, p
    yis, yip = admittances(o.eps, o.k0, kix, kiy)
    yi = np.r_[yis, yip]
    es, ep = polarisations(kix, kiy)
    beta = np.concatenate([md.beta for md in modes])
    ym = np.concatenate([md.y for md in modes])
    G = (O.conj().T * (w * yk)) @ O
    e2 = np.exp(2j * beta * thickness)
    e1 = np.exp(1j * beta * thickness)
    den = np.where(np.abs(e2 - 1) < 1e-12, 1e-12, e2 - 1)
    cot = 1j * (e2 + 1) / den
    csc = 2j * e1 / den
    incs = [np.array([es[0, 0] * e[0] + es[1, 0] * e[1], ep[0, 0] * e[0] + ep[1, 0] * e[1]]) for e in polarisations_in]
    rhs = np.stack([2 * (Oi.conj().T @ (inc * yi)) for inc in incs], axis=1)
    S = np.linalg.solve(G + np.diag(1j * ym * (cot - csc)), rhs)      # E + E'
    D = np.linalg.solve(G + np.diag(1j * ym * (cot + csc)), rhs)      # E - E'
    first = np.isclose(o.kx, kt[0], atol=1e-9 * o.k0) & np.isclose(o.ky, kt[1], atol=1e-9 * o.k0)
    out = []
    for j, inc in enumerate(incs):
        top, bottom = (S[:, j] + D[:, j]) / 2, (S[:, j] - D[:, j]) / 2
        t = O @ bottom
        r = O @ top
        if first.any() and np.all(o.weight == 1):             # a lattice: the specular order carries -inc
            i = int(np.argmax(first))
            r[i] -= inc[0]
            r[o.kx.size + i] -= inc[1]
        p_in = float(np.sum(yi.real * np.abs(inc) ** 2))
        out.append(Solution(top, bottom, t, r, p_in, float(np.sum(w * yk.real * np.abs(t) ** 2)),
                            float(np.sum(w * yk.real * np.abs(r) ** 2))))
    return out
