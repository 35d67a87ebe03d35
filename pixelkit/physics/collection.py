"""Carrier collection in the pixel's silicon: which junction collects a carrier generated where.

Minority carriers diffuse in the quasi-neutral silicon and recombine (lifetime tau = L^2 / D);
a depletion region sweeps every carrier that reaches it into its junction by drift. In steady
state, for a generation G (carriers / s / m^3),

    D grad^2 n - n / tau + G = 0,   n = 0 on every depletion edge,   D dn/dz = S n at the surface,

and the current junction j collects is D times the flux into its depletion edge. Solving that once
per generation (per wavelength and light pattern) would be wasteful: by the reciprocity theorem of
charge collection [Donolato1985] the same current is

    I_j = q (integral of G psi_j over the volume),

where psi_j, the probability that a carrier born at r reaches junction j, solves the adjoint
problem - the same operator (it is self-adjoint), no source, psi_j = 1 on j's depletion regions
(where drift collects every carrier), psi_j = 0 on every other junction's, the same surface
recombination. One solve per junction then serves every wavelength, spectrum and light pattern:
the collection maps are what the kit caches (by geometry).

Discretisation: finite volumes on a tensor grid - uniform lateral spacing ``h`` (periodic or
reflecting sides: a periodic cell is an infinite array of identical pixels, the dual pixel and its
neighbours), layers ``z`` refined at the surface. Each voxel is labelled: 0 quasi-neutral (p-type:
electrons with ``Substrate.electrons``; ``n_type``: holes in an n-well with ``Substrate.holes``),
k >= 1 the collecting (depletion) region of junction k, -1 dead (psi = 0 for every junction: a
contact, a heavily doped tap). A face between a quasi-neutral voxel and a fixed one puts the
boundary on the face (half a voxel of diffusion). The surface is a Robin condition (surface
recombination velocity S in series with the half voxel). Below the last layer the substrate is
homogeneous down to ``Substrate.thickness``: the lateral variation of psi has decayed there
(the layers reach several cell widths down), so the laterally uniform solution of
D psi'' = psi D / L^2 is joined exactly (a Robin condition, D psi' = -D kappa psi, with
kappa = tanh(d / L) / L over a reflecting bottom, coth(d / L) / L over a recombining one, d the
remaining depth), and the generation below is weighted by that continuation
(:meth:`Maps.collected`).

Solver: the sparse system (symmetric positive definite, an M-matrix) by classical (Ruge-Stuben)
algebraic multigrid, the method built for M-matrices, as a conjugate-gradient preconditioner (pyamg)
for the 3D cells, a direct factorisation (SuperLU) for small ones. (Smoothed aggregation with the
evolution strength measure converged in as many iterations but cost three times as much to set up:
the revA pixel's nine maps 23.9 s CPU against 7.1 s, the two within 5e-7 of each other;
``benchmarks/light_map.py`` measures the readout cells.)
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: systems at most this size are factorised directly
DIRECT = 60_000
#: relative residual of the multigrid solves
TOL = 1e-7


@dataclass(frozen=True)
class Carriers:
    """Minority-carrier transport in one kind of quasi-neutral region."""
    diffusivity: float   # m2/s
    length: float        # diffusion length (m); lifetime L^2 / D


@dataclass(frozen=True)
class Substrate:
    electrons: Carriers          # in the p-type substrate
    holes: Carriers              # in the n-wells
    surface_velocity: float      # m/s at the silicon surface
    thickness: float             # m: the lightly doped region the grid and its continuation cover
    bottom: str = "reflecting"   # reflecting (a p+ / p- interface, or a passivated back) or recombining

    def kappa(self, z_bottom: float) -> float:
        """The continuation's D psi' / (D psi) at depth ``z_bottom`` (1/m)."""
        d, L = self.thickness - z_bottom, self.electrons.length
        if d <= 0:
            raise ValueError(f"the substrate ({self.thickness * 1e6:g} um) ends above the grid's bottom "
                             f"({z_bottom * 1e6:g} um)")
        x = d / L
        return (np.tanh(x) if self.bottom == "reflecting" else 1.0 / np.tanh(x)) / L

    def continuation(self, z_bottom: float, depth) -> np.ndarray:
        """psi(z) / psi(z_bottom) below the grid (laterally uniform)."""
        d, L = self.thickness - z_bottom, self.electrons.length
        u = np.clip(np.asarray(depth) - z_bottom, 0.0, d)
        if self.bottom == "reflecting":
            return np.exp(-u / L) * (1 + np.exp(-2 * (d - u) / L)) / (1 + np.exp(-2 * d / L))
        return np.exp(-u / L) * (1 - np.exp(-2 * (d - u) / L)) / (1 - np.exp(-2 * d / L))


@dataclass(frozen=True)
class Grid:
    h: float                 # lateral spacing (m)
    nx: int
    ny: int
    z: np.ndarray            # layer boundaries (m), z[0] = 0 (the surface), increasing
    periodic: tuple = (True, True)

    @property
    def nz(self) -> int:
        return len(self.z) - 1

    @property
    def dz(self) -> np.ndarray:
        return np.diff(self.z)

    @property
    def shape(self) -> tuple:
        return (self.nz, self.ny, self.nx)

    def volumes(self) -> np.ndarray:
        return (self.h * self.h * self.dz)[:, None, None] * np.ones(self.shape)


def layers(depth: float, fine: float, top: float, growth: float = 1.25) -> np.ndarray:
    """Layer boundaries: ``fine`` spacing down to ``top``, then each layer ``growth`` x the one above, to ``depth``."""
    z = list(np.arange(0.0, top + fine / 2, fine))
    step = fine
    while z[-1] < depth * (1 - 1e-12):
        step *= growth
        z.append(z[-1] + step if depth - z[-1] > 1.5 * step else depth)
    return np.array(z)


@dataclass
class Maps:
    """psi of each junction on the grid, and what the continuation below needs."""
    grid: Grid
    substrate: Substrate
    psi: dict                # junction id -> float32 array (nz, ny, nx), 1 in its region, 0 in others
    bottom: dict             # junction id -> psi at the grid's bottom face, lateral mean

    def collected(self, generation: np.ndarray, deep_per_m: callable | None = None) -> dict:
        """{junction: carriers / s} for ``generation`` (carriers / s in each voxel, shape ``grid.shape``);
        ``deep_per_m(z)``: the generation below the grid, laterally integrated (carriers / s / m), or None."""
        out = {}
        w = None
        if deep_per_m is not None:
            zb = self.grid.z[-1]
            zs = zb + np.concatenate([[0.0], np.geomspace(1e-9, self.substrate.thickness - zb, 4000)])
            w = np.trapezoid(deep_per_m(zs) * self.substrate.continuation(zb, zs), zs)
        for k, p in self.psi.items():
            out[k] = float(np.sum(generation * p)) + (w * self.bottom[k] if w is not None else 0.0)
        return out


def _faces(grid: Grid):
    """(a, b, area, distance) of every interior face (flat voxel indices), periodic sides wrapped."""
    nz, ny, nx = grid.shape
    idx = np.arange(nz * ny * nx).reshape(grid.shape)
    dz = grid.dz
    out = []
    for axis, n, per in ((2, nx, grid.periodic[0]), (1, ny, grid.periodic[1])):
        if n == 1 and per:
            continue                      # a single periodic column: no lateral faces
        a = idx if per else np.take(idx, range(n - 1), axis=axis)
        b = np.roll(idx, -1, axis=axis) if per else np.take(idx, range(1, n), axis=axis)
        area = (grid.h * dz)[:, None, None] * np.ones(a.shape)
        out.append((a.ravel(), b.ravel(), area.ravel(), np.full(a.size, grid.h), np.zeros(a.size, bool)))
    a, b = idx[:-1].ravel(), idx[1:].ravel()
    mid = 0.5 * (dz[:-1] + dz[1:])
    out.append((a, b, np.full(a.size, grid.h * grid.h),
                np.repeat(mid, ny * nx), np.ones(a.size, bool)))
    return [np.concatenate(c) for c in zip(*out)]


def solve(grid: Grid, labels: np.ndarray, n_type: np.ndarray, substrate: Substrate,
          junctions: list | None = None) -> Maps:
    """psi of every junction (``labels`` >= 1; ``junctions``: only these ids) on ``grid``.

    ``labels``: int array ``grid.shape`` (0 quasi-neutral, k >= 1 junction k's collecting region, -1 dead);
    ``n_type``: bool array, the quasi-neutral voxels that are n-well (holes) rather than substrate."""
    import scipy.sparse as sp
    labels = np.asarray(labels)
    if labels.shape != grid.shape:
        raise ValueError(f"labels {labels.shape} do not match the grid {grid.shape}")
    ids = sorted(int(k) for k in np.unique(labels) if k >= 1) if junctions is None else list(junctions)
    flat = labels.ravel()
    free = flat == 0
    n_free = int(free.sum())
    num = np.full(flat.size, -1)
    num[free] = np.arange(n_free)
    ntyp = np.asarray(n_type).ravel() & free
    D = np.where(ntyp, substrate.holes.diffusivity, substrate.electrons.diffusivity)
    L = np.where(ntyp, substrate.holes.length, substrate.electrons.length)
    vol = grid.volumes().ravel()
    diag = np.zeros(n_free)
    diag += (vol * D / L ** 2)[free]
    a, b, area, dist, vertical = _faces(grid)
    dz = np.repeat(grid.dz, grid.ny * grid.nx)
    fa, fb = free[a], free[b]
    # free - free
    m = fa & fb
    c = area[m] * 2 * D[a[m]] * D[b[m]] / (D[a[m]] + D[b[m]]) / dist[m]
    rows = np.concatenate([num[a[m]], num[b[m]]])
    cols = np.concatenate([num[b[m]], num[a[m]]])
    vals = np.concatenate([-c, -c])
    np.add.at(diag, num[a[m]], c)
    np.add.at(diag, num[b[m]], c)
    # free - fixed: the boundary on the face (half the free voxel's extent)
    rhs = {k: np.zeros(n_free) for k in ids}
    for f, g in ((a, b), (b, a)):
        m = free[f] & ~free[g]
        half = np.where(vertical[m], dz[f[m]] / 2, grid.h / 2)
        c = area[m] * D[f[m]] / half
        np.add.at(diag, num[f[m]], c)
        for k in ids:
            hit = flat[g[m]] == k
            np.add.at(rhs[k], num[f[m]][hit], c[hit])
    # surface (Robin) and bottom (the continuation's Robin)
    nxy = grid.nx * grid.ny
    top = np.arange(nxy)
    top = top[free[top]]
    A = grid.h * grid.h
    np.add.at(diag, num[top], A / (1.0 / substrate.surface_velocity + dz[top] / (2 * D[top])))
    bot = np.arange(flat.size - nxy, flat.size)
    bot = bot[free[bot]]
    kap = substrate.kappa(grid.z[-1])
    c_bot = A / (1.0 / (D[bot] * kap) + dz[bot] / (2 * D[bot]))
    np.add.at(diag, num[bot], c_bot)
    K = sp.csr_matrix((vals, (rows, cols)), shape=(n_free, n_free)) + sp.diags(diag)
    sol = _solver(K)
    psi, bottom = {}, {}
    for k in ids:
        x = sol(rhs[k])
        full = np.where(flat == k, 1.0, 0.0)
        full[free] = x
        psi[k] = full.reshape(grid.shape).astype(np.float32)
        face = np.zeros(nxy)
        last = full[flat.size - nxy:]
        okb = free[flat.size - nxy:]
        face[okb] = last[okb] / (1 + kap * grid.dz[-1] / 2)
        bottom[k] = float(face.mean())
    return Maps(grid, substrate, psi, bottom)


def _solver(K):
    """x = solve(b) for the SPD matrix ``K``."""
    import scipy.sparse.linalg as sla
    if K.shape[0] <= DIRECT:
        lu = sla.splu(K.tocsc())
        return lu.solve
    import pyamg
    ml = pyamg.ruge_stuben_solver(K.tocsr(), max_coarse=500)

    def run(b):
        if not np.any(b):
            return np.zeros_like(b)
        return ml.solve(b, tol=TOL, accel="cg", maxiter=400)
    return run
