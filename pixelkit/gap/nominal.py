"""Nominal prediction of measured rows: a SPICE-calibrated surrogate, with its own error.

The nominal pixel responds to the charge it collects, Q = (i_ph + I_dark(T)) t_int
(the design's dark current, technology law), so one SPICE sweep of the full chain
(dual pixel + column loads + S1X/S2X + SC AFE, both arrays in each deck, the
experiment's window) over Q gives, per array, the column level at the signal
sample V_sig(Q) and at the reset sample V_rst, as the column really is: loaded by
the AFE's C11, so bright signals that cannot slew within the sampling window are
compressed exactly as on the chip. The AFE probe follows the finite-gain SC
relation of ``measure.afe`` applied to those sampled levels, plus the residual
SPICE shows on the sweep (switch injection, incomplete settling of the AFE
input), interpolated against the signal. Levels are cubic splines of the
charge (linear interpolation left 2 - 3 mV between grid points on the bright,
slewing part). The surrogate's own error is measured against full-chain SPICE
runs at charges between the sweep points and reported with every prediction;
the diagnosis adds it to the measurement noise.

Storage-node (FD-domain) charge does not pass through the PD + FD charge
sharing, and perturbations of the column or the AFE change how far a slewing
column gets: their responses are measured on the nominal deck with one
element at the effect's site (``responses``: FD charge, a load on the column,
the load current, clock coupling onto FD and onto the AFE's virtual ground),
at twelve charges and two amplitudes.

Readout light (``vm_light``): a junction photocurrent I (A, + draws charge out
of the node) on the AFE's virtual-ground node vm. Charge balance of the SC
stage (``circuits.afe``; C11 in-vm, C12 vm-x, C13 vm-c):

- phase 1 (p1, 0.1 .. 0.4 t_row - t_no): vm is tied to Vref by its switch; the
  current flows into Vref and leaves nothing behind;
- from p1 opening (0.4 t_row - t_no) to the output sample (end of phase 2,
  0.9 t_row) vm floats: the island of the capacitor plates on vm (C11, C12,
  C13) loses Q = I t_f, t_f = 0.5 t_row + t_no (the 20 ns non-overlap counts);
- phase 2 (p2): the loop is closed, x is the op-amp's virtual ground and x's
  island (C12 plate, op-amp gate) keeps its charge, so vm returns to where it
  was; the island charge C11 (vm - in) + C12 (vm - x) + C13 (vm - out) then
  changes only through out: dVout = + I t_f / C13 (times 1 / (1 + eps)),
  whatever the signal.

Full-chain SPICE bears this out to 1 - 2 % on the island's charge at every
signal (``tests/test_gap_light.py``). Two things the closed form does not hold, both
of this circuit: (a) before p1 the in node floats too, the current pulls it
(through C11) and S1X dumps that charge on the column, which has not recovered
at the signal sample: a pixel-probe shift of about -0.06 mV per nA on the
secondary, seen by the AFE as a smaller signal; (b) between p1 opening and p2
closing (0.2 t_row) the op-amp runs open loop. At large signals the column is
still slewing down when S1X opens, so even the nominal output heads for the
supply (3.3 - 3.7 V at the end of the gap); the light's extra error on the
floating network (I t / ~20 fF, integrated by the op-amp) takes it to about
3.75 V, where the off feedback switch's p+ junction (out side, n-well at Vdd)
conducts and puts charge on x's island. That charge appears on the output
with gain -(C11 + C12 + C13) / (C12 C13) and opposite sign: at 0.3 - 0.4 V of
signal and a few nA the response turns negative (this op-amp macromodel has no
output rail; a real output stage stops at the supply and would leave the
closed form alone). Both are measured rather than assumed, like the FD
response: ``LIGHT_DECKS`` full-chain decks with known currents on every AFE's
vm at six charges give, per array, the pixel-probe shift and the AFE shift
beyond I t_f / C13, tabulated against signal and current (at the design's read
rates: rows at another ``f_read_Hz`` get t_f from their own rate, the table as is).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from scipy.interpolate import CubicSpline

from ..circuits.testbench import dual_pixel_bench, timings
from ..measure.afe import eps, finite_gain_output
from ..measure.pixel import levels
from ..physics.dark import dark_current
from ..physics.subpixel import pd_node
from .exact import simulate_exact

ARRAYS = ("primary", "secondary")
N_GRID = 22
# readout-light response decks: grid charges, and per deck the vm current of the primary's AFE and of the
# three secondary AFEs (A); both signs, over the range a 3e-11 - 3e-10 m^2 junction sees in a lab campaign
LIGHT_Q_PICK = (2, 5, 7, 9, 10, 11, 12, 13, 15, 17, 20)
LIGHT_I = ((0.5e-9, (0.7e-9, -0.7e-9, 2e-9)), (-0.5e-9, (-2e-9, 4e-9, -4e-9)),
           (5e-9, (8e-9, -8e-9, 20e-9)), (-5e-9, (-20e-9, 50e-9, -50e-9)),
           (1.5e-9, (1.2e-9, -30e-9, 30e-9)), (-1.5e-9, (2.8e-9, -40e-9, -65e-9)),
           (0.3e-9, (-10e-9, -13e-9, -16e-9)), (-0.3e-9, (0.35e-9, 1.6e-9, -25e-9)))


@dataclass
class Nominal:
    q_grid: dict          # array -> Q grid (C)
    v_sig: dict           # array -> column level at the signal sample (V)
    v_rst: dict           # array -> column reset level (V) at each grid charge
    vref: float
    gain_afe: float       # C11 / C13
    eps_afe: float
    afe_resid: dict      # array -> (signal grid V, residual V) of SPICE over the finite-gain relation
    dark: dict            # array -> (area, perimeter)
    pd: object            # technology photodiode section
    error: dict
    light: dict = None     # array -> (signal grid V, vm current grid A, pixel shift V, AFE shift beyond I t_f / C13 V)
    c13: float = 0.0
    sites: dict = None     # site -> ``responses.Response`` (measured response to a perturbation there)
    idle_light: dict = None  # array -> ``idlelight`` table (light on the sampling node while the readout idles)

    def __post_init__(self):
        self._sig = {a: CubicSpline(self.q_grid[a], self.v_sig[a]) for a in ARRAYS}
        self._rst = {a: CubicSpline(self.q_grid[a], self.v_rst[a]) for a in ARRAYS}
        self._res = {a: CubicSpline(*self.afe_resid[a]) for a in ARRAYS}

    def _each(self, arr_idx, x, fns, clip):
        x = np.asarray(x, float)
        ck = (id(fns), x.tobytes(), arr_idx.tobytes())
        cache = self.__dict__.setdefault("_cache", {})
        if ck in cache:
            return cache[ck]
        if len(cache) > 256:
            cache.clear()
        cache[ck] = out = self._each_new(arr_idx, x, fns, clip)
        out.setflags(write=False)
        return out

    def _each_new(self, arr_idx, x, fns, clip):
        out = np.empty_like(np.asarray(x, float))
        for k, a in enumerate(ARRAYS):
            m = arr_idx == k
            lo, hi = clip[a]
            out[m] = fns[a](np.clip(x[m], lo, hi))
        return out

    def _qclip(self):
        return {a: (self.q_grid[a][0], self.q_grid[a][-1]) for a in ARRAYS}

    def as_dict(self) -> dict:
        """Everything but the technology section, as JSON-ready lists (floats round-trip exactly)."""
        def arr(x):
            return np.asarray(x, float).tolist()
        return {"q_grid": {a: arr(v) for a, v in self.q_grid.items()}, "v_sig": {a: arr(v) for a, v in self.v_sig.items()},
                "v_rst": {a: arr(v) for a, v in self.v_rst.items()}, "vref": self.vref, "gain_afe": self.gain_afe,
                "eps_afe": self.eps_afe, "afe_resid": {a: [arr(x) for x in v] for a, v in self.afe_resid.items()},
                "dark": {a: list(v) for a, v in self.dark.items()}, "error": self.error,
                "light": {a: [arr(x) for x in v] for a, v in self.light.items()}, "c13": self.c13,
                "sites": {k: r.as_dict() for k, r in self.sites.items()},
                **({} if self.idle_light is None else
                   {"idle_light": {a: [arr(x) for x in v] for a, v in self.idle_light.items()}})}

    @classmethod
    def from_dict(cls, d: dict, pd) -> "Nominal":
        from .responses import Response
        def arrs(m):
            return {a: np.array(v) for a, v in m.items()}
        return cls(arrs(d["q_grid"]), arrs(d["v_sig"]), arrs(d["v_rst"]), d["vref"], d["gain_afe"], d["eps_afe"],
                   {a: tuple(np.array(x) for x in v) for a, v in d["afe_resid"].items()},
                   {a: tuple(v) for a, v in d["dark"].items()}, pd, d["error"],
                   {a: tuple(np.array(x) for x in v) for a, v in d["light"].items()}, d["c13"],
                   {k: Response.from_dict(r) for k, r in d["sites"].items()},
                   None if "idle_light" not in d else
                   {a: tuple(np.array(x) for x in v) for a, v in d["idle_light"].items()})

    def vsig_of(self, arr_idx, q):
        # beyond the grid (the swing's end): the column stays at its last level (saturated)
        return self._each(arr_idx, q, self._sig, self._qclip())

    def vrst_of(self, arr_idx, q=None):
        if q is None:
            return np.where(arr_idx == 0, self.v_rst["primary"].mean(), self.v_rst["secondary"].mean())
        return self._each(arr_idx, q, self._rst, self._qclip())

    @property
    def fd_ratio(self) -> dict:
        """Per array: (grid charges, equivalent PD charge per unit FD charge at the smaller FD amplitude)."""
        r = self.sites["fd"]
        return {a: (r.q[a], r.tables[a]["dq"][:, 0] / r.amps[a][0]) for a in ARRAYS}

    def site(self, name, key, arr_idx, q, amp):
        """The measured response ``key`` of site ``name`` (``responses``) at each row."""
        return self.sites[name].at(key, arr_idx, q, amp)

    def dark_q(self, arr_idx, temp_C, t_int):
        out = np.empty_like(t_int)
        for k, a in enumerate(ARRAYS):
            m = arr_idx == k
            area, per = self.dark[a]
            out[m] = dark_current(area, per, temp_C[m] + 273.15, self.pd) * t_int[m]
        return out

    def vm_light(self, arr_idx, signal, i_vm, t_float):
        """(pixel-probe shift, AFE shift) of a current ``i_vm`` on the AFE's vm node (module docstring):
        the charge-balance term i_vm t_float / C13 plus the measured column kick and op-amp clamp."""
        pix = np.zeros_like(signal)
        afe = i_vm * t_float / self.c13 / (1 + self.eps_afe)
        if not self.light:
            return pix, afe
        for k, a in enumerate(ARRAYS):
            m = arr_idx == k
            sg, ig, tp, ta = self.light[a]
            pix[m] = _bilinear(sg, ig, tp, signal[m], i_vm[m])
            afe[m] += _bilinear(sg, ig, ta, signal[m], i_vm[m])
        return pix, afe

    def afe(self, arr_idx, signal, eps_extra=0.0):
        e = self.eps_afe + eps_extra
        out = self.vref - self.gain_afe * signal / (1 + e)
        clip = {a: (self.afe_resid[a][0][0], self.afe_resid[a][0][-1]) for a in ARRAYS}
        return out + self._each(arr_idx, signal, self._res, clip)


def _bilinear(sg, ig, table, s, i):
    """Table over (signal, current): linear in current (extrapolated), linear in signal (clipped)."""
    k = np.clip(np.searchsorted(ig, i) - 1, 0, len(ig) - 2)
    wi = (i - ig[k]) / (ig[k + 1] - ig[k])
    sc = np.clip(s, sg[0], sg[-1])
    j = np.clip(np.searchsorted(sg, sc) - 1, 0, len(sg) - 2)
    ws = (sc - sg[j]) / (sg[j + 1] - sg[j])

    def at(row):
        return table[row, k] * (1 - wi) + table[row, k + 1] * wi
    return at(j) * (1 - ws) + at(j + 1) * ws


def t_float(design, f_read, arr):
    """How long vm floats before the AFE's output sample: p1 opens t_no before S1 does (the array's
    ``timing.s1_off``), the output is sampled when S2 opens (``s2_off``), at row time 1 / ``f_read``
    (array or scalar); ``arr``: the array's name or index (0 primary, 1 secondary), or an array of indices."""
    t_row = 1.0 / np.asarray(f_read, float)

    def span(kind):
        ph = getattr(design, kind).timing.row(t_row)
        return ph["s2_off"] - ph["s1_off"]
    if isinstance(arr, str):
        return span(arr) + design.afe.nonoverlap
    return np.where(np.asarray(arr) == 0, span("primary"), span("secondary")) + design.afe.nonoverlap


def _light_deck(design, qp, qs, i_p, i_s, title):
    """The nominal deck with a vm current on every AFE (``i_p`` on the primary's, ``i_s`` per secondary)."""
    from .circuit_edits import add_to_subckt, specialise, vm_current
    t_w = design.experiment.t_window
    net = specialise(dual_pixel_bench(design, qp / t_w, qs / t_w, with_afe=True, title=title),
                     design.secondary_per_pixel)
    net = add_to_subckt(net, "scafe_col_p", vm_current(design, "primary", i_p))
    for k, i in enumerate(i_s):
        net = add_to_subckt(net, f"scafe_col_s{k}", vm_current(design, "secondary", i))
    return net


def _light_table(design, tm, sweep, res, sig):
    """Per array: (signal grid, current grid incl. 0, pixel shift, AFE shift beyond the charge-balance term)."""
    out = {}
    for arr, cols in (("primary", ("col_p",)), ("secondary", tuple(f"col_s{k}" for k in range(3)))):
        t = tm[arr]
        tf = t_float(design, 1.0 / t.t_row, arr)
        pts = {}
        for n, k in enumerate(LIGHT_Q_PICK):
            base_pix, _ = levels(sweep[k], "col_s0" if arr == "secondary" else "col_p", t)
            base_out = float(sweep[k].at("out_" + ("col_s0" if arr == "secondary" else "col_p"), t.t_reset_level(0)))
            for j, (i_p, i_s) in enumerate(LIGHT_I):
                r = res[n * len(LIGHT_I) + j]
                for c, i in zip(cols, (i_p,) if arr == "primary" else i_s):
                    dpix = levels(r, c, t)[0] - base_pix
                    dout = float(r.at(f"out_{c}", t.t_reset_level(0))) - base_out
                    lin = i * tf / design.afe.c13 / (1 + eps(design.afe.c11, design.afe.c13, design.afe.gain))
                    pts[(k, i)] = (dpix, dout - lin)
        ig = np.array(sorted({i for _, i in pts} | {0.0}))
        sg = np.array([sig[arr][k] for k in LIGHT_Q_PICK])
        tp = np.array([[pts.get((k, i), (0.0, 0.0))[0] for i in ig] for k in LIGHT_Q_PICK])
        ta = np.array([[pts.get((k, i), (0.0, 0.0))[1] for i in ig] for k in LIGHT_Q_PICK])
        out[arr] = (sg, ig, tp, ta)
    return out


def _q_max(design, which):
    node = pd_node(design, which, parasitics=True)
    return float(node.charge(design.pixel.v_pd_reset) - node.charge(0.5))


def _invert(q, v_sig):
    """Charge at a signal level, through the sweep (the level falls with charge; clipped to the grid)."""
    f = CubicSpline(q, v_sig)
    fine = np.linspace(q[0], q[-1], 4000)
    lv = f(fine)

    def inv(level):
        return float(np.interp(-level, -lv, fine))
    return inv


VAL_PICK = (3, 9, 12, 15, 18)


def grids(design) -> dict:
    """The sweep's charges per array (denser at low charge)."""
    u = np.linspace(0.0, 1.0, N_GRID) ** 1.5
    return {"primary": u * _q_max(design, "primary"), "secondary": u * _q_max(design, "secondary")}


def stage_one(design, ends_only: bool = False) -> list:
    """The sweep, the validation decks between its charges and the readout-light decks (``ends_only``: of
    each kind only those at the first and last of its charges, ``store.deck_key``'s sample)."""
    t_w = design.experiment.t_window
    g = grids(design)
    qp, qs = g["primary"], g["secondary"]

    def ends(ks):
        return (ks[0], ks[-1]) if ends_only else ks
    nets = [dual_pixel_bench(design, qp[k] / t_w, qs[k] / t_w, with_afe=True, title=f"gapnom{k}")
            for k in ends(range(len(qp)))]
    mid_p, mid_s = (qp[1:] + qp[:-1]) / 2, (qs[1:] + qs[:-1]) / 2
    nets += [dual_pixel_bench(design, mid_p[k] / t_w, mid_s[k] / t_w, with_afe=True, title=f"gapval{k}")
             for k in ends(VAL_PICK)]
    nets += [_light_deck(design, qp[k], qs[k], i_p, i_s, f"gaplt{k}_{j}") for k in ends(LIGHT_Q_PICK)
             for j, (i_p, i_s) in enumerate(LIGHT_I)]
    return nets


def build_nominal(design, backend: str = "batch") -> Nominal:
    """The surrogate from SPICE (``store.load_nominal`` uses a shipped one when its decks are these)."""
    from . import idlelight, responses
    t_w = design.experiment.t_window
    tm = timings(design, t_w)
    g = grids(design)
    qp, qs = g["primary"], g["secondary"]
    a = design.afe
    mid_p, mid_s = (qp[1:] + qp[:-1]) / 2, (qs[1:] + qs[:-1]) / 2
    pick = VAL_PICK
    nets = stage_one(design)
    res = simulate_exact(nets, backend=backend)
    n0 = N_GRID + len(pick)
    sweep, val, lt = res[:N_GRID], res[N_GRID:n0], res[n0:]
    v_sig, v_rst, resid, sig_grid, outs, lvls, inv = {}, {}, {}, {}, {}, {}, {}
    for arr, col, q in (("primary", "col_p", qp), ("secondary", "col_s0", qs)):
        lv = np.array([levels(r, col, tm[arr]) for r in sweep])
        lvls[arr] = lv
        v_sig[arr], v_rst[arr] = lv[:, 0], lv[:, 1]
        sig_grid[arr] = lv[:, 1] - lv[:, 0]
        out = np.array([float(r.at(f"out_{col}", tm[arr].t_reset_level(0))) for r in sweep])
        outs[arr] = out
        sig = lv[:, 1] - lv[:, 0]
        order = np.argsort(sig)
        resid[arr] = (sig[order], (out - finite_gain_output(a.vref, a.c11, a.c13, a.gain, sig))[order])
        inv[arr] = _invert(q, lv[:, 0])
    q_grid = g
    pivots = {arr: float(v_rst[arr].mean()) for arr in ARRAYS}
    plan = responses.decks(design, q_grid, pivots)
    site_res = simulate_exact([p[3] for p in plan], backend=backend)
    sites = responses.tables(design, plan, site_res, q_grid, lvls, outs, lambda arr, lv: inv[arr](lv))
    nom = Nominal(q_grid, v_sig, v_rst, a.vref, a.c11 / a.c13,
                  eps(a.c11, a.c13, a.gain), resid,
                  {w: (getattr(design, w).area, getattr(design, w).perimeter) for w in ARRAYS},
                  design.tech.photodiode, {}, _light_table(design, tm, sweep, lt, sig_grid), a.c13, sites,
                  idlelight.build(design, q_grid, backend))
    errs_pix, errs_afe = [], []
    for k, r in zip(pick, val):
        for arr, col, q in (("primary", "col_p", mid_p[k]), ("secondary", "col_s0", mid_s[k])):
            idx = np.array([ARRAYS.index(arr)])
            s_lvl, r_lvl = levels(r, col, tm[arr])
            qq = np.array([q])
            pred = nom.vsig_of(idx, qq)[0]
            errs_pix.append(pred - s_lvl)
            sig = nom.vrst_of(idx, qq) - np.array([pred])
            errs_afe.append(nom.afe(idx, sig)[0] - float(r.at(f"out_{col}", tm[arr].t_reset_level(0))))
    nom.error = {"pixel_max_V": float(np.max(np.abs(errs_pix))), "afe_max_V": float(np.max(np.abs(errs_afe))),
                 "pixel_rms_V": float(np.sqrt(np.mean(np.square(errs_pix)))),
                 "afe_rms_V": float(np.sqrt(np.mean(np.square(errs_afe)))), "n_validation": len(errs_pix),
                 "loose_decks": [r.meta["title"] for r in list(res) + list(site_res) if r.meta.get("retried")],
                 "fd_ratio": {k: [float(x) for x in v[1]] for k, v in nom.fd_ratio.items()}}
    return nom


def features(table, nom: Nominal, design) -> dict:
    """The row quantities the models use, as arrays (with the nominal signal of each row).

    ``J`` is the irradiance at the row's array as a photocurrent density (A/m^2,
    the row's photocurrent over its subpixel's photoactive area): stray-light
    effects scale with it times the exposed area of their structure. ``t_hold``
    is the readout's row time (1 / ``f_read_Hz`` when the data carry it, else the
    design's per-array read rate); ``t_float`` how long the AFE's vm node floats
    before the output sample (``t_float``).
    """
    cols = table.columns
    prev = cols.get("i_ph_prev_A")
    i = table.num("i_ph_A")
    arr = np.array([ARRAYS.index(a) for a in cols["array"]])
    a_pa = np.where(arr == 0, design.primary.photoactive_area, design.secondary.photoactive_area)
    f_design = np.where(arr == 0, design.primary.f_read, design.secondary.f_read)
    f_read = cols.get("f_read_Hz")
    f_read = f_design if f_read is None else np.where(np.isfinite(f_read), f_read, f_design)
    vdd = cols.get("vdd_V")
    vdd = np.full(i.size, design.tech.supply) if vdd is None else np.where(np.isfinite(vdd), vdd, design.tech.supply)
    X = {"arr": arr, "row": table.num("row"), "col": table.num("col"), "i": i,
         "t_int": table.num("t_int_s"), "t_wait": table.num("t_wait_s"), "T": table.num("temp_C"),
         "afe": np.array([p == "afe" for p in cols["probe"]]),
         "i_prev": i.copy() if prev is None else np.where(np.isfinite(prev), prev, i),
         "has_prev": prev is not None,
         "perimeter_ratio": design.secondary.perimeter / design.primary.perimeter,
         "J": i / a_pa, "a_ref": design.primary.photoactive_area,
         "a_sub": np.where(arr == 0, design.primary.area, design.secondary.area),
         "f_read": f_read, "f_design": f_design, "t_hold": 1.0 / f_read, "t_float": t_float(design, f_read, arr),
         "vdd": vdd, "dvdd": vdd - design.tech.supply, "has_idle_light": nom.idle_light is not None}
    q = i * X["t_int"] + nom.dark_q(X["arr"], X["T"], X["t_int"])
    X["q"] = q
    X["signal"] = nom.vrst_of(arr, q) - nom.vsig_of(arr, q)
    return X


LEVEL_SITES = ("col_g", "load", "rst_fd", "p1_vm", "sf_w", "c11", "a_ol")


def predict(nom: Nominal, X: dict, terms: dict | None = None) -> np.ndarray:
    """Column-level (pixel probe) or AFE-output prediction of each row, with effect ``terms``.

    ``terms`` may hold ``dq`` (extra PD charge, C), ``fd`` (extra charge on the
    storage node FD during its hold, C: the measured site response), ``dv_pix``
    (signal shift in the pixel / column chain, positive = more signal, V: it
    pivots at the reset level), ``dv_col`` (pixel-probe level shift that double
    sampling cancels), ``deps`` (extra AFE gain error), ``dv_afe`` (AFE output
    shift, V), ``dv_out`` (shift of both probes' output stage, V), ``i_vm``
    (junction current on the AFE's vm node, A: ``Nominal.vm_light``), ``i_idle``
    (junction current on the sampling node while the readout idles, A: ``idlelight``), and the
    amplitude of a measured site response (``responses``): ``col_g`` (S),
    ``load`` (relative), ``rst_fd`` (F), ``p1_vm`` (F, signed), ``sf_w`` and ``c11`` (relative),
    ``a_ol`` (A_design / A - 1 of the op-amp).
    """
    t = terms or {}
    q = X["q"] + t.get("dq", 0.0)
    if "fd" in t:
        q = q + nom.site("fd", "dq", X["arr"], q, t["fd"])
    vs = nom.vsig_of(X["arr"], q)
    vr = nom.vrst_of(X["arr"], q)
    signal = vr - vs + t.get("dv_pix", 0.0)
    v_pix = vr - signal + t.get("dv_col", 0.0)
    v_afe = nom.afe(X["arr"], signal, t.get("deps", 0.0)) + t.get("dv_afe", 0.0)
    for name in LEVEL_SITES:
        if name in t:
            v_pix = v_pix + nom.site(name, "pix", X["arr"], q, t[name])
            v_afe = v_afe + nom.site(name, "afe", X["arr"], q, t[name])
    if "i_vm" in t:
        lp, la = nom.vm_light(X["arr"], signal, np.broadcast_to(t["i_vm"], signal.shape).astype(float), X["t_float"])
        v_pix, v_afe = v_pix + lp, v_afe + la
    if "i_idle" in t:
        from .idlelight import response
        lp, la = response(nom.idle_light, X["arr"], signal, np.broadcast_to(t["i_idle"], signal.shape).astype(float))
        v_pix, v_afe = v_pix + lp, v_afe + la
    return np.where(X["afe"], v_afe, v_pix) + t.get("dv_out", 0.0)
