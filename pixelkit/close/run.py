"""One close: a trust-region method on SPICE-built linear models, every candidate re-verified by
``verify`` (docs/close.md, "How it works").

1. The start (the design's knob values, clipped into their bounds) is verified on the whole grid.
2. The specs within ``margins.ACTIVE`` of their target are modelled, each at its worst condition and
   the next within ``margins.BAND`` of it: each knob is moved by a fixed step (3 % of a lin knob's
   span or of a log knob's value) and the groups those specs need are simulated there
   (``verify.run.measure_at``): forward differences give each (spec, condition) margin's gradient.
   A row keeps its gradient from step to step as the candidates' secants correct it (Broyden); all
   are refreshed after a poorly predicted step, after ``REFRESH_EVERY`` steps, and before a verdict.
3. casadi solves the step (``close.step``): while a margin is below its target, the step that
   raises the smallest margin most; once every target is met on the whole grid, the step that
   improves the objective keeping every modelled margin >= its target.
4. The candidate is simulated at the modelled conditions and each spec's worst condition: rejected
   there when it gives less than ``ETA`` of what the model promised or breaks a spec nothing modelled
   (modelled from then on); a second-order correction is tried when the objective improved but a
   modelled margin curved past its target. A candidate still short at those conditions (restoring), or
   passing them once the design passes (optimising), is judged there, without the grid; the first that
   passes them is verified on the whole grid (``verify.run.verify``), and so is the optimum the loop
   ends on (failing somewhere unscreened: back to the last grid-verified revision, that condition
   modelled). A grid-verified candidate is accepted only when the whole grid says so (the smallest margin rose;
   or, once passing, it still passes and the objective improved). A rejection halves the trust
   region below the step that failed.
5. It ends when the model's next step is below ``[close] tolerance`` on fresh sensitivities: with a
   passing revision, its Monte Carlo yield is checked (``[verify] mc``; each spec's yield interval's
   lower bound must reach ``min_yield``: if not, the spec's margin target at the nominal condition is
   raised to its Monte Carlo spread and the loop goes on); without one, the rows whose multipliers
   carry the max-min step (``close.step.restore``) are the specs that conflict.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import ConfigError
from ..verify import conditions
from ..verify.run import measure_at, suite, verify
from . import margins as mg
from .knobs import Space, at_bound, check_bounds
from .objective import of as objective_of
from .step import Model, correct, optimise, restore

#: Finite-difference step in knob coordinates (3 % of a span or of a value).
FD_STEP = 0.03
#: First trust region (20 % of a span or of a value) and its largest.
RADIUS0, RADIUS_MAX = 0.2, 1.0
#: Accept a step at the modelled conditions when it gives at least this share of what the model said.
ETA = 0.1
#: Restore aims this far inside every target (a share of the limit), so that the candidate the model
#: puts on the limit is not just outside it in SPICE.
CUSHION = 0.002
#: A step that promises less than this (smallest margin, or objective relative to its start) is none.
PROMISE = 1e-5
#: Refresh every gradient by finite differences after this many accepted steps on secants alone.
REFRESH_EVERY = 3
#: While restoring, a trust region that collapsed below the tolerance (candidates the models did not
#: predict: a figure not smooth in the knobs) is reopened this many times with fresh sensitivities.
RESTARTS = 2
#: A collapsed region is a max-min point (infeasible) when the models, within the first region, see less
#: than this share of the shortfall recoverable (rows that balance); else the candidates broke the models.
BALANCED = 0.5
#: A max-min point is a proof of infeasibility (for the linear models) only at a trust region this large.
PROOF_RADIUS = 0.05
#: The key of the objective's gradient (a figure at the nominal condition).
OBJECTIVE = ("objective", None)
#: Rounds of "raise the nominal targets to the Monte Carlo spread" before close gives up on yield.
YIELD_ROUNDS = 3
#: A knob counts as moving a figure when the figure changes by more than this (relative).
MOVES = 1e-12


@dataclass
class Point:
    """A design close simulated on the whole grid."""
    x: np.ndarray
    design: object
    values: dict                  # {condition: {figure: SI}}
    margins: dict                 # {(spec, condition): normalised margin}
    f: float | None               # objective (SI)
    errors: list = field(default_factory=list)
    signoff: dict | None = None   # verify's result (without Monte Carlo)


def cpu_s() -> float:
    """CPU seconds (user + system) of this process and of every child it waited for: with the batch
    backend, every ngspice run (the worker threads wait for theirs as each ends)."""
    import resource
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


class _Counter:
    """SPICE runs and cache hits of the whole close, read per iteration."""

    def __init__(self):
        from ..spice.counter import SpiceCounter
        self.c = SpiceCounter(lambda _c: None)
        self.mark = (0, 0)
        self.cpu_mark = cpu_s()

    def cpu(self) -> float:
        """CPU seconds (this process and its ngspice runs) since the last call."""
        now = cpu_s()
        out, self.cpu_mark = now - self.cpu_mark, now
        return out

    def delta(self) -> tuple[int, int]:
        now = (self.c.runs, self.c.cached)
        out = (now[0] - self.mark[0], now[1] - self.mark[1])
        self.mark = now
        return out


class Closer:
    """One close of the numeric ``knobs`` (default: the design's) from ``design`` as it is.
    ``refuse_idle``: a knob that moves nothing is refused (exit 2); else it is kept still and listed
    in ``idle`` (under a circuit choice it may have no effect, as a gate rail with the gates on the supply)."""

    def __init__(self, design, backend="batch", jobs=None, scheduler=None, tell=None, say=None, knobs=None,
                 refuse_idle: bool = True, label: str = ""):
        self.base, self.backend, self.jobs, self.scheduler = design, backend, jobs, scheduler
        self.tell, self.say = tell or (lambda _t: None), say or (lambda _t: None)
        self.refuse_idle, self.label, self.idle = refuse_idle, label, []
        self.space = Space(tuple(knobs if knobs is not None else design.close.knobs))
        self.suite = suite(design)       # the measurement groups and figures of its family
        self.objective = objective_of(design)
        self.grid = conditions.grid(design)
        self.nominal = conditions.nominal(design)
        self.settings = design.close
        self.targets: dict = {}          # (spec, condition) -> normalised margin target
        self.spec = {s.name: s for s in design.spec}
        self.iterations: list = []
        self.t0 = time.perf_counter()
        self.counter = _Counter()
        self.yield_check = _yield_needs(design)
        self.f_scale = None
        self.tried: list = []            # every candidate's knob values
        self.grads: dict = {}            # (spec, condition) or OBJECTIVE -> gradient in u (kept across steps)
        self.explored: dict = {}         # the global stage's record (close.explore)

    # --- evaluation ---------------------------------------------------------------------------
    def target(self, key) -> float:
        return self.targets.get(key, self.settings.margin)

    def full(self, x, design=None) -> Point:
        d = design or self.space.design(self.base, x)
        r = verify(d, mc=0, backend=self.backend, jobs=self.jobs, scheduler=self.scheduler)
        by_label = {c.label: c for c in self.grid}
        values = {by_label[c["label"]]: c["figures"] for c in r["conditions"]}
        f = self.objective_value(d, values.get(self.nominal))
        return Point(x, d, values, mg.table(d, self.grid, values), f, r["errors"], r)

    def objective_value(self, design, nominal_figs) -> float | None:
        fig = self.objective.figure
        if fig and (nominal_figs is None or nominal_figs.get(fig) is None):
            (out,) = measure_at([(design, self.nominal, self.suite.groups_for([fig]))], backend=self.backend,
                                jobs=self.jobs, scheduler=self.scheduler, desc="objective")
            nominal_figs = out["figures"]
        return self.objective.value(design, nominal_figs)

    def cm(self, key, m) -> float:
        """The margin ``m`` less its target as the models see it: itself when passing, -ln(1 - x) when short
        by x (a figure orders of magnitude outside its limit - an op-amp that slews, a gain error of 80 % -
        is modelled on its logarithm, where one linear step does not promise to undo it all; same sign,
        same slope at the limit)."""
        if m is None or not np.isfinite(m):
            return np.nan
        x = m - self.target(key)
        return x if x >= 0 else -math.log1p(-x)

    def fnorm(self, f: float | None) -> float | None:
        """The objective as minimised: normalised by its start value, negated for max."""
        if f is None:
            return None
        return (1.0 if self.objective.sense == "min" else -1.0) * f / self.f_scale

    def smallest(self, margins: dict) -> float:
        return min(((m if m is not None else -math.inf) - self.target(k) for k, m in margins.items()),
                   default=math.inf)

    # --- the models -----------------------------------------------------------------------------
    def plan(self, pairs) -> tuple[list, dict]:
        """(conditions, {condition: groups}) that measure ``pairs`` (and the objective at nominal)."""
        fig = self.objective.figure
        groups = self.groups(pairs, {self.nominal: self.suite.groups_for([fig])} if fig else None)
        return sorted(groups), groups

    def groups(self, pairs, into: dict | None = None) -> dict:
        """{condition: measurement groups, in the suite's order} that measure the (spec, condition)
        ``pairs``, added to those of ``into``."""
        out = {c: set(g) for c, g in (into or {}).items()}
        for name, c in pairs:
            out.setdefault(c, set()).update(self.suite.groups_for([self.spec[name].fig.name]))
        return self.ordered(out)

    def ordered(self, groups: dict) -> dict:
        """{condition: groups} with each condition's groups as a tuple in the suite's order."""
        order = list(self.suite.GROUPS)
        return {c: tuple(sorted(g, key=order.index)) for c, g in groups.items()}

    def rows(self, groups: dict) -> list:
        """Every (spec, condition) the planned groups measure (more rows than bind, at no cost)."""
        out = []
        for s in self.base.spec:
            for c in conditions.spec_conditions(s, list(groups)):
                if set(self.suite.groups_for([s.fig.name])) <= set(groups[c]):
                    out.append((s.name, c))
        return out

    def at(self, designs: list, conds: list, groups: dict, desc: str) -> list[dict]:
        """{condition: figures} for each design (the planned groups at the planned conditions)."""
        items = [(d, c, groups[c]) for d in designs for c in conds]
        outs = measure_at(items, backend=self.backend, jobs=self.jobs, scheduler=self.scheduler, desc=desc)
        per = []
        for i in range(len(designs)):
            per.append({c: outs[i * len(conds) + k]["figures"] for k, c in enumerate(conds)})
        return per

    def row_margins(self, rows, figs: dict) -> np.ndarray:
        return np.array([mg.margin(self.spec[n], figs.get(c, {}).get(self.spec[n].fig.name)) if
                         mg.margin(self.spec[n], figs.get(c, {}).get(self.spec[n].fig.name)) is not None
                         else np.nan for n, c in rows])

    def model(self, p: Point, pairs, first: bool) -> tuple[Model, list, dict, bool]:
        """The linear models of the margins of ``pairs`` (and of every other spec the same groups measure
        there) and of the objective at ``p``: (model, conditions, groups, whether every gradient is fresh).
        A row modelled before keeps its gradient, as the secants of the candidates since corrected it
        (Broyden: a quasi-Newton model); a row new to the model gets finite differences (at its
        conditions only). ``self.grads.clear()`` makes them all fresh."""
        conds, groups = self.plan(pairs)
        rows = [r for r in self.rows(groups) if p.margins.get(r) is not None]
        obj = self.objective.figure is not None
        need = {c for r in rows if r not in self.grads for c in [r[1]]}
        if obj and OBJECTIVE not in self.grads:
            need.add(self.nominal)
        if first:
            need = set(conds)
        xs, du = self.fd_points(p)
        designs = [p.design] + [self.space.design(self.base, x) for x in xs]
        if need:
            fd_conds = sorted(need)
            self.tell(f"sensitivities: {self.space.n} knobs x {len(fd_conds)} conditions")
            figs = self.at(designs, fd_conds, {c: groups[c] for c in fd_conds}, "sensitivities")
            fd_rows = [r for r in self.rows({c: groups[c] for c in fd_conds}) if r in set(rows)]
            m_base = [self.cm(r, m) for r, m in zip(fd_rows, self.row_margins(fd_rows, figs[0]))]
            for i, r in enumerate(fd_rows):
                self.grads[r] = np.array([_slope(self.cm(r, self.row_margins([r], figs[j + 1])[0]), m_base[i], du[j])
                                          for j in range(self.space.n)])
            if obj and self.nominal in need:
                f_base = self.fnorm(figs[0].get(self.nominal, {}).get(self.objective.figure))
                self.grads[OBJECTIVE] = np.array([_slope(self.fnorm(figs[j + 1].get(self.nominal, {}).get(
                    self.objective.figure)), f_base, du[j]) for j in range(self.space.n)])
            if first:
                self._refuse_idle_knobs(fd_rows, figs, designs)
        elif first:    # nothing modelled yet: the dependence check on every spec's groups alone
            self._refuse_idle_knobs([], [{}] * len(designs), designs)
        fresh = first or all(r[1] in need for r in rows)
        m0 = np.array([self.cm(r, p.margins[r]) for r in rows])
        g = np.array([self.grads.get(r, np.zeros(self.space.n)) for r in rows]).reshape(len(rows), self.space.n)
        f0 = self.fnorm(p.f)
        if obj:
            gf = self.grads.get(OBJECTIVE, np.zeros(self.space.n)).copy()
        else:   # a closed form (area, a knob): exact differences, no simulation
            gf = np.array([_slope(self.fnorm(self.objective.value(designs[j + 1], None)), f0, du[j])
                           for j in range(self.space.n)])
        return Model(rows, m0, g, f0, gf), conds, groups, fresh

    def fd_points(self, p: Point) -> tuple[list, list]:
        """The knob values of the finite differences at ``p`` (one knob moved each) and the moves in u."""
        u0 = self.space.to_u(p.x)
        lo, hi = self.space.u_bounds
        xs, du = [], []
        for j, k in enumerate(self.space.knobs):
            h = FD_STEP
            if k.grid:   # at least two grid steps
                h = max(h, 2 * (k.grid / p.x[j] if k.log else k.grid / (k.hi - k.lo)))
            u = u0.copy()
            u[j] = u0[j] + h if u0[j] + h <= hi[j] else u0[j] - h
            x = self.space.snap(self.space.to_x(u))
            xs.append(x)
            du.append(self.space.to_u(x)[j] - u0[j])
        return xs, du

    def keep_secant(self, model: Model) -> None:
        """The models' rows, corrected by a candidate's secant, are the gradients from now on."""
        for i, r in enumerate(model.keys):
            self.grads[r] = model.g[i].copy()
        if self.objective.figure is not None:
            self.grads[OBJECTIVE] = model.gf.copy()

    def _refuse_idle_knobs(self, rows, figs, designs) -> None:
        """A knob that moves no figure of any spec nor the objective is refused (or, under a circuit
        choice, kept still). First at the modelled conditions (its sensitivities, no extra run); a knob
        that moved nothing there is tried on every spec's measurements at the nominal condition (and at
        the first condition of each spec that does not hold there): the specs with a large margin are
        not modelled, and a knob may move only those."""
        names = {self.spec[n].fig.name for n, _ in rows} | ({self.objective.figure} if self.objective.figure else set())
        suspects = [j for j in range(self.space.n) if not self._moves(j, figs, designs, names)]
        if not suspects:
            return
        groups: dict = {}
        for sp in self.base.spec:
            held = conditions.spec_conditions(sp, [self.nominal] + self.grid)
            if held:
                groups.setdefault(held[0], set()).update(self.suite.groups_for([sp.fig.name]))
        groups = self.ordered(groups)
        more = self.at([designs[0]] + [designs[j + 1] for j in suspects], sorted(groups), groups, "dependence")
        every = {sp.fig.name for sp in self.base.spec}
        for i, j in enumerate(suspects):
            k = self.space.knobs[j]
            if self._moves(i, more, [designs[0]] + [designs[j + 1] for j in suspects], every):
                continue
            if not self.refuse_idle:
                self.idle.append(k.name)
                self.say(f"close{self.label}: {k.name} moves no spec here: kept where it is")
                continue
            raise ConfigError(self.base.source, f"close.knobs.{k.name}", k.name,
                              "a knob some spec depends on: moving it by "
                              f"{100 * FD_STEP:g} % changed no figure of any spec (at its binding conditions and at "
                              f"{', '.join(c.label for c in sorted(groups))}) nor the objective")

    def _moves(self, j: int, figs: list, designs: list, names: set) -> bool:
        """Whether design j + 1 of ``designs`` differs from design 0 in a figure of ``names`` or the objective."""
        base = figs[0]
        if any(_moved(base.get(c, {}).get(f), figs[j + 1].get(c, {}).get(f)) for c in base for f in names):
            return True
        return not self.objective.figure and _moved(self.objective.value(designs[0], None),
                                                    self.objective.value(designs[j + 1], None))

    # --- the loop -------------------------------------------------------------------------------
    def run(self) -> dict:
        with self.counter.c:
            return self._run()

    def _run(self) -> dict:
        s = self.settings
        check_bounds(self.space, self.base)
        x0, notes = self.space.start(self.base)
        for n in notes:
            self.say(n)
        self.tell("verifying the start on the whole grid")
        p = self.full(x0)
        self.f_scale = abs(p.f) if p.f else 1.0
        self.record(p, accepted=True, mode="start", radius=None, where="grid")
        if self.smallest(p.margins) < 0:   # failing: the global stage over a cheap bench's knobs first
            from .explore import explore
            xg, self.explored = explore(self, p)
            if xg is not None:
                self.tell("verifying the global stage's choice on the whole grid")
                pg = self.full(xg)
                better = self.smallest(pg.margins) > self.smallest(p.margins)
                self.record(pg, accepted=better, mode="global", radius=None, where="grid")
                if better:
                    p = pg
        radius, forced, first, status, last, shrunk, on_secants = RADIUS0, set(), True, None, None, False, 0
        anchor, restarts = p, RESTARTS

        def stall():
            """Restoring, the trust region collapsed: reopen it on fresh sensitivities (at most RESTARTS
            times), then ``stalled``: no passing revision found, which is not a proof that none exists."""
            nonlocal radius, restarts, last
            now = float(model.m.min()) if len(model.m) else 0.0
            wide = restore(model, u0, lo, hi, RADIUS0, CUSHION)   # what the models see within the first region
            if wide.t - now < BALANCED * max(-now, CUSHION):   # they see no way up either: a max-min point
                last = (wide, model, RADIUS0)
                return "infeasible"
            if not restarts:
                return "stalled"
            restarts -= 1
            radius = RADIUS0
            self.grads.clear()
            self.say(f"close{self.label}: the trust region collapsed while restoring; reopened at {RADIUS0} on "
                     f"fresh sensitivities ({restarts} more)")
            return None
        yield_rounds, yield_result = 0, None
        if not self.space.n:   # nothing numeric to move (a circuit choice alone): the start is the answer
            status = "converged" if self.smallest(p.margins) >= 0 else "infeasible"
            if status == "converged" and self.yield_check:
                yield_result = self.check_yield(p)
        while status is None:
            pairs = set(mg.binding(self.base, p.margins, self.targets, s.margin)) | set(self.targets) | forced
            model, conds, groups, fresh = self.model(p, sorted(pairs, key=lambda r: (r[0], r[1])), first)
            first, built_fresh = False, fresh
            u0 = self.space.to_u(p.x)
            lo, hi = self.space.u_bounds
            while status is None:
                if self.candidates() >= s.max_iterations:
                    status = "stopped"
                    break
                feasible = self.smallest(p.margins) >= 0
                mode = "optimise" if feasible else "restore"
                st = (optimise(model, u0, lo, hi, radius, CUSHION) if feasible
                      else restore(model, u0, lo, hi, radius, CUSHION))
                last = (st, model, radius)
                xc = self.space.snap(self.space.to_x(u0 + st.d))
                now = float(model.m.min()) if len(model.m) else 0.0
                promise = (model.f - st.f) if feasible else st.t - now
                small = float(np.abs(st.d).max()) < s.tolerance
                if (feasible and (np.array_equal(xc, p.x) or promise <= PROMISE or small)
                        or not feasible and st.t < CUSHION and small):
                    if fresh:   # the model's next move is below the tolerance: passing, or a max-min point
                        status = ("converged" if feasible else "infeasible" if radius >= PROOF_RADIUS else stall())
                    else:       # on secants: sure of it only with fresh sensitivities
                        self.grads.clear()
                    break
                if not feasible and (np.array_equal(xc, p.x) or promise <= PROMISE):
                    if fresh and radius >= PROOF_RADIUS:   # no step raises the smallest margin: a max-min point
                        status = "infeasible"
                    elif fresh or radius <= s.tolerance:   # within a collapsed region: reopen it first
                        status = stall()
                    else:                                  # else: fresh sensitivities at this point
                        self.grads.clear()
                    break
                if _seen(xc, self.tried):   # the models (fresh ones too) point where a candidate already failed
                    radius /= 2
                    shrunk = True
                    if radius < s.tolerance:
                        status = "converged" if feasible else stall()
                        if status is None:
                            break
                    continue
                sconds, sgroups, screen = self.screen(p, conds, groups)
                targets = np.array([self.target(r) for r in model.keys])
                xc, dc, cf, fc, local, bad = self.attempt(xc, model, st, feasible, sconds, sgroups, screen, p, targets)
                fresh = False
                measured = np.all(np.isfinite(self.row_margins(model.keys, cf)))
                if local < ETA and not bad and feasible and fc is not None and fc < model.f and measured:
                    # (a candidate where a modelled spec was not measured - its deck failed - has no margin to
                    # correct onto: it is rejected as it is)
                    # the objective improved but a modelled constraint curved away: a second-order
                    # correction, back onto the passing side, before giving the step up
                    self.record_partial(xc, cf, model.keys + screen, fc, mode, radius)
                    m_at = np.array([self.cm(k, m) for k, m in zip(model.keys, self.row_margins(model.keys, cf))])
                    d2 = correct(model, m_at, st.d, u0, lo, hi, radius, CUSHION)
                    x2 = self.space.snap(self.space.to_x(u0 + d2))
                    mode = "optimise, corrected"
                    if np.array_equal(x2, xc) or _seen(x2, self.tried):
                        radius /= 2
                        shrunk = True
                        if radius < s.tolerance:
                            status = "converged"
                        continue
                    st = replace(st, d=d2)
                    xc, dc, cf, fc, local, bad = self.attempt(x2, model, st, feasible, sconds, sgroups, screen, p, targets)
                forced |= bad
                if local < ETA:
                    self.record_partial(xc, cf, model.keys + screen, fc, mode, radius)
                    radius = min(radius, float(np.abs(st.d).max())) / 2   # below the step that failed
                    shrunk = True     # no growth on the next success: the radius just failed
                    if radius < s.tolerance:
                        status = "converged" if feasible else stall()
                        if status is None:
                            break
                    if bad:
                        break         # a spec nothing modelled broke: model it (its sensitivities) first
                    continue
                on_screen = feasible or self.smallest(self.screened_margins(dc, sgroups, cf)) < 0
                if on_screen:   # judged where it was simulated: the grid when the design first passes there, and
                    # for the optimum (below)
                    pc = self.screened(xc, dc, sgroups, cf, fc)
                else:
                    self.tell(f"candidate {self.candidates() + 1}: verifying on the whole grid")
                    pc = self.full(xc, dc)
                ok, rho = self.accept(p, pc, feasible, st)
                self.record(pc, accepted=ok, mode=mode, radius=radius,
                            where="modelled and worst conditions" if on_screen else "grid")
                if ok:
                    if pc.signoff is not None and self.smallest(pc.margins) >= 0:
                        anchor = pc    # the last revision that passed on the whole grid
                    p = pc
                    grow = rho > 0.75 and float(np.abs(st.d).max()) >= 0.99 * radius and not shrunk
                    radius = min(2 * radius, RADIUS_MAX) if grow else radius if rho > 0.25 else radius / 2
                    shrunk = False
                    on_secants = 0 if built_fresh else on_secants + 1
                    if rho < 0.5 or on_secants >= REFRESH_EVERY:
                        self.grads.clear()    # the models predicted poorly, or have run on secants long enough
                    break
                radius = min(radius, float(np.abs(st.d).max())) / 2
                shrunk = True
                new = set() if on_screen else {k for k, m in pc.margins.items()
                                               if (m is None or m - self.target(k) < 0) and k not in pairs}
                if radius < s.tolerance:
                    status = "converged" if feasible else stall()
                    if status is None:
                        break
                elif new:     # it failed where nothing was modelled: model the worst of those from now on
                    forced |= set(sorted(new, key=lambda k: -math.inf if pc.margins[k] is None else pc.margins[k])[:3])
                    break
            if status == "converged" and p.signoff is None:   # the optimum, judged on screens: its whole grid
                self.tell("verifying the optimum on the whole grid")
                pg = self.full(p.x, p.design)
                short = {k for k, m in pg.margins.items() if m is None or m - self.target(k) < 0}
                self.record(pg, accepted=not short, mode="grid check", radius=radius, where="grid")
                if short:      # it failed where no screen looked: back to the last grid-verified revision,
                    # those conditions modelled from now on
                    forced |= set(sorted(short, key=lambda k: -math.inf if pg.margins[k] is None else pg.margins[k])[:3])
                    p, status, radius = anchor, None, RADIUS0
                    self.grads.clear()
                    continue
                p = anchor = pg
            if status == "converged" and self.yield_check:
                yield_result = self.check_yield(p)
                if not yield_result["ok"] and yield_rounds < YIELD_ROUNDS and yield_result.get("targets"):
                    yield_rounds += 1
                    self.targets.update(yield_result["targets"])
                    status, radius = None, RADIUS0
        if p.signoff is None:   # ended on a candidate judged where it was simulated: its whole grid, for the record
            self.tell("verifying the last candidate on the whole grid")
            pg = self.full(p.x, p.design)
            passes = self.smallest(pg.margins) >= 0
            self.record(pg, accepted=passes, mode="final", radius=None, where="grid")
            p = pg if passes or self.smallest(anchor.margins) < 0 else anchor   # else the last that passed the grid
        return self.result(p, status, last, yield_result)

    def screened_margins(self, design, groups: dict, figs: dict) -> dict:
        """{(spec, condition): margin} of the rows the simulated ``groups`` measure at their conditions."""
        return {k: m for k, m in mg.table(design, sorted(groups), figs).items() if k in set(self.rows(groups))}

    def screened(self, x, design, groups: dict, figs: dict, fc) -> Point:
        """A candidate judged at the conditions it was simulated at (the modelled ones and each spec's worst),
        not on the whole grid: while restoring, a candidate still short there needs no grid to say so."""
        f = None if fc is None else fc * self.f_scale * (1 if self.objective.sense == "min" else -1)
        return Point(x, design, figs, self.screened_margins(design, groups, figs), f)

    def screen(self, p: Point, conds: list, groups: dict) -> tuple[list, dict, list]:
        """The conditions a candidate is simulated at before the whole grid: the modelled ones and each
        spec's worst condition at ``p`` (a spec with a large margin is not modelled, but a step that
        breaks it is caught here, at a fraction of the grid's cost); and those (spec, worst) pairs."""
        screen = [(name, c) for name, (m, c) in mg.worst(self.base, p.margins).items() if c is not None]
        out = self.groups(screen, groups)
        return sorted(out), out, screen

    def attempt(self, xc, model, st, feasible, conds, groups, screen, p: Point, targets):
        """Simulate candidate ``xc`` at ``conds``: (xc, its figures, objective, the share of the promised
        gain it gave, the screened pairs it broke). The models take its secant."""
        self.tell(f"candidate {self.candidates() + 1}: {len(conds)} conditions (modelled, and each spec's worst)")
        self.tried.append(xc)
        dc = self.space.design(self.base, xc)
        cf = self.at([dc], conds, groups, "candidate")[0]
        m_rows = np.array([self.cm(k, m) for k, m in zip(model.keys, self.row_margins(model.keys, cf))])
        fc = self.fnorm(self.objective_value(dc, cf.get(self.nominal)))
        local = _local_gain(model, m_rows, feasible, fc, st)
        _secant(model, st.d, m_rows, fc)
        self.keep_secant(model)
        floor = 0.0 if feasible else self.smallest(p.margins)
        bad = set()
        for k in screen:
            m = mg.margin(self.spec[k[0]], cf.get(k[1], {}).get(self.spec[k[0]].fig.name))
            if m is None or m - self.target(k) < floor:
                bad.add(k)
        if bad - set(model.keys):
            local = -1.0   # an unmodelled spec broke (or fell below the current worst): model it from now on
        return xc, dc, cf, fc, local, bad - set(model.keys)

    def candidates(self) -> int:
        """Candidates simulated so far (the start is not one)."""
        return len(self.iterations) - 1

    def accept(self, p: Point, pc: Point, feasible: bool, st) -> tuple[bool, float]:
        w, wc = self.smallest(p.margins), self.smallest(pc.margins)
        if pc.errors:
            return False, 0.0
        if feasible:
            if wc < 0 or pc.f is None:
                return False, 0.0
            gain, promised = self.fnorm(p.f) - self.fnorm(pc.f), self.fnorm(p.f) - st.f
            return gain > 0, gain / promised if promised > 0 else 1.0
        gain, promised = wc - w, st.t - w
        return gain > 0, gain / promised if promised > 0 else 1.0

    # --- yield -----------------------------------------------------------------------------------
    def check_yield(self, p: Point) -> dict:
        from .yields import check
        v = self.base.verify
        self.tell(f"Monte Carlo yield: {v.mc} samples at {self.nominal.label}")
        r = verify(p.design, backend=self.backend, jobs=self.jobs, scheduler=self.scheduler)
        out = check(self.base, r, self.nominal, p.margins)
        runs, cached = self.counter.delta()
        out.update(spice_runs=runs, spice_cached=cached, cpu_s=self.counter.cpu(), samples=r["mc"].get("samples")
                   if isinstance(r.get("mc"), dict) else None)
        self.say(out["text"])
        return {**out, "signoff": r}

    # --- records ---------------------------------------------------------------------------------
    def _specs(self, margins: dict) -> dict:
        out = {}
        for name, (m, c) in mg.worst(self.base, margins).items():
            out[name] = {"margin_pct": None if m is None else 100 * m, "where": None if c is None else c.label,
                         "target_pct": 100 * max((self.target(k) for k in margins if k[0] == name), default=0.0)}
        return out

    def record(self, p: Point, accepted: bool, mode: str, radius, where: str) -> None:
        runs, cached = self.counter.delta()
        rec = {"iteration": len(self.iterations), "mode": mode, "accepted": accepted, "verified_on": where,
               "knobs": self.space.overrides(p.x), "radius": radius,
               "smallest_margin_pct": _pct(self.smallest(p.margins)), "objective": p.f,
               "specs": self._specs(p.margins), "errors": p.errors[:5], "spice_runs": runs, "spice_cached": cached,
               "cpu_s": self.counter.cpu(), "wall_s": time.perf_counter() - self.t0}
        self.iterations.append(rec)
        from .output import iteration_text
        self.say(iteration_text(rec, self.objective, self.label))

    def record_partial(self, x, figs: dict, keys, fc, mode: str, radius) -> None:
        m = {k: mg.margin(self.spec[k[0]], figs.get(k[1], {}).get(self.spec[k[0]].fig.name)) for k in keys}
        runs, cached = self.counter.delta()
        rec = {"iteration": len(self.iterations), "mode": mode, "accepted": False,
               "verified_on": "modelled and worst conditions", "knobs": self.space.overrides(x), "radius": radius,
               "smallest_margin_pct": _pct(self.smallest(m)),
               "objective": None if fc is None else fc * self.f_scale * (1 if self.objective.sense == "min" else -1),
               "specs": self._specs(m), "errors": [], "spice_runs": runs, "spice_cached": cached,
               "cpu_s": self.counter.cpu(), "wall_s": time.perf_counter() - self.t0}
        self.iterations.append(rec)
        from .output import iteration_text
        self.say(iteration_text(rec, self.objective, self.label))

    def result(self, p: Point, status: str, last, yield_result) -> dict:
        from .output import _obj, conflicts
        signoff = (yield_result or {}).get("signoff") or p.signoff
        unmeasured = list(signoff["unmeasured"]) if signoff else []
        short = [k for k, m in p.margins.items() if m is not None and m - self.target(k) < 0]
        if any(m is None for m in p.margins.values()) and not unmeasured:
            unmeasured = sorted({k[0] for k, m in p.margins.items() if m is None})
        yield_ok = yield_result is None or yield_result["ok"]
        if short:
            status = status if status in ("infeasible", "stalled") else "not closed"
        elif not yield_ok:
            status = "yield not met"
        elif unmeasured:
            status = "not measured"
        else:
            status = "closed" if status == "converged" else "passing"
        start = self.iterations[0]
        out = {"design": self.base.name, "source": self.base.source, "status": status,
               "passes": status in ("closed", "passing"),
               "objective": {"goal": self.objective.label(), "value": p.f, "start": start["objective"],
                             "shown": _obj(p.f, self.objective), "shown_start": _obj(start["objective"], self.objective)},
               "knobs": [{"key": k.name, "min": self.space.texts([k.lo], [k])[0],
                          "max": self.space.texts([k.hi], [k])[0], "scale": "log" if k.log else "lin",
                          "start": start["knobs"][k.name], "value": self.space.overrides(p.x)[k.name],
                          "at_bound": at_bound(k, x), "tied": list(k.tied)} for k, x in zip(self.space.knobs, p.x)],
               "overrides": self.space.overrides(p.x), "margin_target_pct": 100 * self.settings.margin,
               "tolerance": self.settings.tolerance,
               "targets": [{"spec": k[0], "condition": k[1].label, "target_pct": 100 * v} for k, v in
                           self.targets.items()],
               "iterations": self.iterations, "final": self._specs(p.margins),
               "smallest_margin_pct": _pct(self.smallest(p.margins)),
               "signoff": None if signoff is None else {k: signoff[k] for k in ("rows", "grid", "mc", "power", "failed",
                                                                                "unmeasured", "errors", "view")},
               "yield": None if yield_result is None else {k: v for k, v in yield_result.items()
                                                           if k not in ("signoff", "targets")},
               "spice_runs": sum(i["spice_runs"] for i in self.iterations),
               "spice_cached": sum(i["spice_cached"] for i in self.iterations),
               "wall_s": time.perf_counter() - self.t0, "unmeasured": unmeasured, "idle": list(self.idle),
               "global": self.explored,
               "design_obj": p.design}
        if short and last is not None and status == "infeasible":   # a stall's last step proves no conflict
            out["conflict"] = conflicts(self, p, last)
        return out


def _pct(x: float) -> float | None:
    """A margin in % for the record: None when it is not a number (a spec not measured: JSON has no -inf)."""
    return 100 * x if math.isfinite(x) else None


def _slope(a, b, h) -> float:
    return (a - b) / h if a is not None and b is not None and np.isfinite(a) and np.isfinite(b) and h else 0.0


def _seen(x, tried) -> bool:
    return any(np.array_equal(x, t) for t in tried)


def _moved(a, b) -> bool:
    if a is None or b is None:
        return a is not b
    return abs(a - b) > MOVES * max(abs(a), abs(b), 1e-300)


def _secant(model: Model, d, m_actual, f_actual) -> None:
    """Broyden's correction of the linear models by what a candidate at u0 + d really gave."""
    dd = float(d @ d)
    if dd <= 0:
        return
    ok = np.isfinite(m_actual)
    resid = np.where(ok, m_actual - (model.m + model.g @ d), 0.0)
    model.g += np.outer(resid, d) / dd
    if f_actual is not None and model.f is not None:
        model.gf += (f_actual - (model.f + model.gf @ d)) * d / dd


def _local_gain(model: Model, got_rows, feasible: bool, fc, st) -> float:
    """Share of the promised improvement the candidate gave at the modelled conditions (margins
    less targets ``got_rows``); -1 when it broke a target while passing or was not measured."""
    if not np.all(np.isfinite(got_rows)):
        return -1.0
    now = float(model.m.min()) if len(model.m) else 0.0
    got = float(got_rows.min()) if len(got_rows) else 0.0
    if feasible:
        if got < 0 or fc is None:
            return -1.0
        promised = model.f - st.f
        return (model.f - fc) / promised if promised > 0 else 0.0
    promised = st.t - now
    return (got - now) / promised if promised > 0 else 0.0


def _yield_needs(design) -> bool:
    return bool(design.verify.mc)
