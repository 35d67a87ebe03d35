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

    def length(self, q: float = 0.0) -> float:
        """The decay length of a lateral variation exp(i q . r) of psi in the homogeneous substrate:
        D (psi'' - q^2 psi) = psi D / L^2, so 1 / sqrt(1 / L^2 + q^2) (L itself when laterally uniform)."""
        return 1.0 / np.sqrt(self.electrons.length ** -2 + q * q)

    def kappa(self, z_bottom: float, q: float = 0.0) -> float:
        """The continuation's D psi' / (D psi) at depth ``z_bottom`` (1/m), for psi laterally uniform or
        varying as exp(i q . r) (``q``: its wavevector's magnitude, a Bloch solve's)."""
        d, L = self.thickness - z_bottom, self.length(q)
        if d <= 0:
            raise ValueError(f"the substrate ({self.thickness * 1e6:g} um) ends above the grid's bottom "
                             f"({z_bottom * 1e6:g} um)")
        x = d / L
        return (np.tanh(x) if self.bottom == "reflecting" else 1.0 / np.tanh(x)) / L

    def continuation(self, z_bottom: float, depth, q: float = 0.0) -> np.ndarray:
        """psi(z) / psi(z_bottom) below the grid (laterally uniform, or as exp(i q . r))."""
        d, L = self.thickness - z_bottom, self.length(q)
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
    q: tuple = (0.0, 0.0)    # a Bloch solve's wavevector (1/m): psi complex, psi(r + a) = exp(i q . a) psi(r)

    def collected(self, generation: np.ndarray, deep_per_m: callable | None = None) -> dict:
        """{junction: carriers / s} for ``generation`` (carriers / s in each voxel, shape ``grid.shape``);
        ``deep_per_m(z)``: the generation below the grid, laterally integrated (carriers / s / m), or None."""
        out = {}
        w = None
        if deep_per_m is not None:
            zb = self.grid.z[-1]
            zs = zb + np.concatenate([[0.0], np.geomspace(1e-9, self.substrate.thickness - zb, 4000)])
            qr = float(np.hypot(*reduced(self.q, self.grid)))
            w = np.trapezoid(deep_per_m(zs) * self.substrate.continuation(zb, zs, qr), zs)
        for k, p in self.psi.items():
            v = np.sum(generation * p) + (w * self.bottom[k] if w is not None else 0.0)
            out[k] = complex(v) if np.iscomplexobj(p) else float(v)
        return out


def _faces(grid: Grid):
    """(a, b, area, distance, vertical, wrap) of every interior face (flat voxel indices), periodic sides
    wrapped; ``wrap`` is 1 (x) or 2 (y) where b is a's neighbour across the cell's high side (b lies at the
    low end: b's image beyond the side is the neighbour), 0 elsewhere."""
    nz, ny, nx = grid.shape
    idx = np.arange(nz * ny * nx).reshape(grid.shape)
    dz = grid.dz
    out = []
    for code, (axis, n, per) in enumerate(((2, nx, grid.periodic[0]), (1, ny, grid.periodic[1])), start=1):
        if n == 1 and per:
            continue                      # a single periodic column: no lateral faces
        a = idx if per else np.take(idx, range(n - 1), axis=axis)
        b = np.roll(idx, -1, axis=axis) if per else np.take(idx, range(1, n), axis=axis)
        area = (grid.h * dz)[:, None, None] * np.ones(a.shape)
        wrap = np.zeros(a.shape, np.int8)
        if per:
            np.moveaxis(wrap, axis, 0)[n - 1] = code
        out.append((a.ravel(), b.ravel(), area.ravel(), np.full(a.size, grid.h), np.zeros(a.size, bool), wrap.ravel()))
    a, b = idx[:-1].ravel(), idx[1:].ravel()
    mid = 0.5 * (dz[:-1] + dz[1:])
    out.append((a, b, np.full(a.size, grid.h * grid.h),
                np.repeat(mid, ny * nx), np.ones(a.size, bool), np.zeros(a.size, np.int8)))
    return [np.concatenate(c) for c in zip(*out)]


def solve(grid: Grid, labels: np.ndarray, n_type: np.ndarray, substrate: Substrate,
          junctions: list | None = None) -> Maps:
    """psi of every junction (``labels`` >= 1; ``junctions``: only these ids) on ``grid``.

    ``labels``: int array ``grid.shape`` (0 quasi-neutral, k >= 1 junction k's collecting region, -1 dead);
    ``n_type``: bool array, the quasi-neutral voxels that are n-well (holes) rather than substrate."""
    sys = _System(grid, labels, n_type, substrate, junctions)
    K, rhs = sys.matrix((0.0, 0.0))
    sol = _solver(K)
    return sys.maps({k: sol(b) for k, b in rhs.items()}, (0.0, 0.0))


def solve_bloch(grid: Grid, labels: np.ndarray, n_type: np.ndarray, substrate: Substrate, qs: list,
                junctions: list | None = None) -> dict:
    """{q: Maps} of Bloch solves: for each wavevector ``q`` = (qx, qy) (1/m) the complex psi_q of every
    junction on a periodic ``grid`` with psi_q(r + a) = exp(i q . a) psi_q(r) for a cell vector a.

    psi_q is the lattice sum of the collection probability psi^(0) of the junction of the cell at the origin
    alone (every other cell's junctions collecting, psi = 0 there): psi_q(r) = sum over cells n of
    psi^(0)(r - a_n) exp(i q . a_n); so averaging exp(i q . a_k) psi_q over the M x M wavevectors
    q = 2 pi (i / (M X), j / (M Y)) gives psi^(0)(r + a_k), the probability that a carrier born in cell k
    reaches the origin's junction (an M x M supercell's answer; :func:`neighbour_collection`). The matrix is
    Hermitian positive definite: solved by conjugate gradients preconditioned by the q = 0 (periodic)
    system's multigrid in the gauge psi = exp(i q . r) u (u periodic: the phase spread over every face
    rather than jumping at the cell's side; 11 iterations against 87 on the revA pixel's 0.5 um grid), or
    directly when small."""
    sys = _System(grid, labels, n_type, substrate, junctions)
    K0, _ = sys.matrix((0.0, 0.0))
    pre = None
    out = {}
    for q in qs:
        q = (float(q[0]), float(q[1]))
        mq = reduced((-q[0], -q[1]), grid)
        twin = next((p for p in out if np.allclose(reduced(p, grid), mq, rtol=0, atol=1e-9 * abs(np.pi / grid.h))), None)
        if twin is not None:                      # psi_-q = conj(psi_q): the operator is real
            m = out[twin]
            out[q] = Maps(grid, substrate, {k: np.conj(v) for k, v in m.psi.items()},
                          {k: np.conj(v) for k, v in m.bottom.items()}, q)
            continue
        K, rhs = sys.matrix(q)
        if K.shape[0] <= DIRECT:
            import scipy.sparse.linalg as sla
            sol = sla.splu(K.tocsc()).solve
        else:
            if pre is None:
                pre = _preconditioner(K0)
            sol = _pcg(K, _gauged(pre, sys.phases(q)) if any(reduced(q, grid)) else pre)
        out[q] = sys.maps({k: sol(b) for k, b in rhs.items()}, q)
    return out


def neighbour_collection(bloch: dict, cells: tuple, generation, deep_per_m=None, offsets=None) -> dict:
    """{(i, j): {junction: carriers / s}}: what the origin cell's junctions collect of ``generation`` (a cell's
    voxels, and its ``deep_per_m`` below the grid as in :meth:`Maps.collected`) lit in the cell at offset
    (i, j) alone (its neighbours dark), from the M x M Bloch solves ``bloch`` (``cells`` = (M, M): q on the
    M x M grid); ``offsets``: the cells wanted (default every cell of the M x M supercell, -M//2 .. M//2).
    Their sum over the supercell is the periodic (every cell lit) collection."""
    mx, my = cells
    m0 = next(iter(bloch.values()))
    X, Y = m0.grid.nx * m0.grid.h, m0.grid.ny * m0.grid.h
    if offsets is None:
        offsets = [(i, j) for j in range(-(my // 2), my - my // 2) for i in range(-(mx // 2), mx - mx // 2)]
    per_q = {q: m.collected(generation, deep_per_m) for q, m in bloch.items()}
    out = {}
    for (i, j) in offsets:
        acc = {}
        for q, col in per_q.items():
            ph = np.exp(1j * (q[0] * i * X + q[1] * j * Y))
            for k, v in col.items():
                acc[k] = acc.get(k, 0.0) + ph * v
        out[(i, j)] = {k: float(v.real) / (mx * my) for k, v in acc.items()}
    return out


def reduced(q, grid: Grid) -> tuple:
    """``q`` brought into the first Brillouin zone of ``grid``'s cell (the same Bloch problem: q and q + 2 pi / X
    give the same phases); its magnitude is the lateral variation's slowest wavevector, the one the continuation
    below the grid keeps."""
    X, Y = grid.nx * grid.h, grid.ny * grid.h
    return tuple(float(v - 2 * np.pi / P * np.round(v * P / (2 * np.pi))) for v, P in zip(q, (X, Y)))


def bloch_wavevectors(grid: Grid, cells: tuple) -> list:
    """The M x N wavevectors (1/m) of an M x N supercell of ``grid``'s cell (the Brillouin zone sampled
    M x N times: q = 2 pi (i / (M X), j / (N Y)), i = 0 .. M - 1)."""
    X, Y = grid.nx * grid.h, grid.ny * grid.h
    return [(2 * np.pi * i / (cells[0] * X), 2 * np.pi * j / (cells[1] * Y))
            for j in range(cells[1]) for i in range(cells[0])]


class _System:
    """The finite-volume system of a cell (free voxels numbered), assembled for any Bloch wavevector."""

    def __init__(self, grid, labels, n_type, substrate, junctions):
        labels = np.asarray(labels)
        if labels.shape != grid.shape:
            raise ValueError(f"labels {labels.shape} do not match the grid {grid.shape}")
        self.grid, self.substrate = grid, substrate
        self.ids = sorted(int(k) for k in np.unique(labels) if k >= 1) if junctions is None else list(junctions)
        self.flat = flat = labels.ravel()
        self.free = free = flat == 0
        self.n_free = int(free.sum())
        self.num = np.full(flat.size, -1)
        self.num[free] = np.arange(self.n_free)
        ntyp = np.asarray(n_type).ravel() & free
        self.D = np.where(ntyp, substrate.holes.diffusivity, substrate.electrons.diffusivity)
        self.L = np.where(ntyp, substrate.holes.length, substrate.electrons.length)
        self.faces = _faces(grid)
        self.dz = np.repeat(grid.dz, grid.ny * grid.nx)
        self.vol = grid.volumes().ravel()

    def matrix(self, q):
        """(K, {junction: right-hand side}) at Bloch wavevector ``q`` (complex unless q = 0)."""
        import scipy.sparse as sp
        grid, flat, free, num, D = self.grid, self.flat, self.free, self.num, self.D
        a, b, area, dist, vertical, wrap = self.faces
        bloch = bool(q[0] or q[1])
        phase = np.ones(a.size, complex if bloch else float)      # psi at b's image = phase x psi_b
        if bloch:
            phase[wrap == 1] = np.exp(1j * q[0] * grid.nx * grid.h)
            phase[wrap == 2] = np.exp(1j * q[1] * grid.ny * grid.h)
        diag = np.zeros(self.n_free)
        diag += (self.vol * D / self.L ** 2)[free]
        m = free[a] & free[b]
        c = area[m] * 2 * D[a[m]] * D[b[m]] / (D[a[m]] + D[b[m]]) / dist[m]
        rows = np.concatenate([num[a[m]], num[b[m]]])
        cols = np.concatenate([num[b[m]], num[a[m]]])
        vals = np.concatenate([-c * phase[m], -c * np.conj(phase[m])])
        np.add.at(diag, num[a[m]], c)
        np.add.at(diag, num[b[m]], c)
        # free - fixed: the boundary on the face (half the free voxel's extent), at its image's phase
        rhs = {k: np.zeros(self.n_free, phase.dtype) for k in self.ids}
        for f, g, ph in ((a, b, phase), (b, a, np.conj(phase))):
            m = free[f] & ~free[g]
            half = np.where(vertical[m], self.dz[f[m]] / 2, grid.h / 2)
            c = area[m] * D[f[m]] / half
            np.add.at(diag, num[f[m]], c)
            for k in self.ids:
                hit = flat[g[m]] == k
                np.add.at(rhs[k], num[f[m]][hit], (c * ph[m])[hit])
        # surface (Robin) and bottom (the continuation's Robin, at the lateral variation's decay length)
        nxy = grid.nx * grid.ny
        top = np.arange(nxy)
        top = top[free[top]]
        A = grid.h * grid.h
        np.add.at(diag, num[top], A / (1.0 / self.substrate.surface_velocity + self.dz[top] / (2 * D[top])))
        bot = np.arange(flat.size - nxy, flat.size)
        bot = bot[free[bot]]
        kap = self.substrate.kappa(grid.z[-1], float(np.hypot(*reduced(q, grid))))
        np.add.at(diag, num[bot], A / (1.0 / (D[bot] * kap) + self.dz[bot] / (2 * D[bot])))
        K = sp.csr_matrix((vals, (rows, cols)), shape=(self.n_free, self.n_free)) + sp.diags(diag)
        return K.tocsr(), rhs

    def phases(self, q) -> np.ndarray:
        """exp(i q . r) at the free voxels' centres (q brought into the first Brillouin zone)."""
        grid = self.grid
        qr = reduced(q, grid)
        x = (np.arange(grid.nx) + 0.5) * grid.h
        y = (np.arange(grid.ny) + 0.5) * grid.h
        ph = np.exp(1j * (qr[1] * y[:, None] + qr[0] * x[None, :]))
        return np.broadcast_to(ph[None], grid.shape).ravel()[self.free]

    def maps(self, solutions: dict, q) -> Maps:
        grid, flat, free = self.grid, self.flat, self.free
        nxy = grid.nx * grid.ny
        kap = self.substrate.kappa(grid.z[-1], float(np.hypot(*reduced(q, grid))))
        psi, bottom = {}, {}
        for k, x in solutions.items():
            full = np.where(flat == k, 1.0, 0.0).astype(x.dtype)
            full[free] = x
            psi[k] = full.reshape(grid.shape).astype(np.complex64 if np.iscomplexobj(x) else np.float32)
            face = np.zeros(nxy, x.dtype)
            last = full[flat.size - nxy:]
            okb = free[flat.size - nxy:]
            face[okb] = last[okb] / (1 + kap * grid.dz[-1] / 2)
            m = face.mean()
            bottom[k] = complex(m) if np.iscomplexobj(m) else float(m)
        return Maps(grid, self.substrate, psi, bottom, (float(q[0]), float(q[1])))


def _preconditioner(K):
    """The multigrid V-cycle of the real SPD ``K`` as a linear operator on complex vectors too."""
    import pyamg
    import scipy.sparse.linalg as sla
    ml = pyamg.ruge_stuben_solver(K.tocsr(), max_coarse=500)
    M = ml.aspreconditioner(cycle="V")

    def apply(r):
        r = np.asarray(r).ravel()
        if np.iscomplexobj(r):
            return M.matvec(np.ascontiguousarray(r.real)) + 1j * M.matvec(np.ascontiguousarray(r.imag))
        return M.matvec(r)
    return sla.LinearOperator(K.shape, matvec=apply, dtype=complex)


def _gauged(M, phase):
    """The preconditioner ``M`` of a periodic system applied to u = conj(phase) r, turned back by ``phase``."""
    import scipy.sparse.linalg as sla
    return sla.LinearOperator(M.shape, matvec=lambda r: phase * M.matvec(np.conj(phase) * np.asarray(r).ravel()),
                              dtype=complex)


def _pcg(K, M):
    """x = solve(b) for the Hermitian positive definite ``K`` by conjugate gradients preconditioned by ``M``."""
    import scipy.sparse.linalg as sla

    def run(b):
        if not np.any(b):
            return np.zeros_like(b)
        x, info = sla.cg(K, b, rtol=TOL, maxiter=1000, M=M)
        if info:
            raise RuntimeError(f"Bloch collection solve did not converge ({info} iterations)")
        return x
    return run


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
