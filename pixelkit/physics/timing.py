"""The global-shutter sequence: its switch intervals and sample instants (pure arithmetic: the
models use it too; ``testbench.waveform`` draws the intervals as PWL sources).

    0 .. t_reset + t_hold   EC on (PD reset), RST on (FD reset)
    t_reset + t_hold        EC opens: exposure starts (all pixels of the array)
    t_tx - t_tg - t_gap     RST opens (FD released before the transfer)
    t_tx - t_tg .. t_tx     TG on: global transfer; exposure ends when TG opens
    t_tx .. t_read          storage: the charge waits on FD (t_pre + t_store); with
                            ``ec_hold`` EC closes again after the transfer and holds
                            the PD in reset (anti-blooming), else the PD keeps
                            integrating and can overflow
    t_read + r t_row        row r: RS on; S1 samples the signal; RST pulses (FD
                            reset); S2 samples the reset level (non-correlated
                            double sampling, [Thesis2019] fig. 3.3); RS off. The phases
                            are the design's ``[<array>.timing]`` keys
                            (``pixelkit.readout_timing``), times from the row's
                            start; absent ones are fractions of the row time.

Each array has its own row time 1/f_read (defaults 500 kHz primary, 1 MHz
secondary). Edges take ``edge`` seconds; levels are 0 and the supply.

The two arrays have their own exposure (thesis: 1 ms primary, 12 ms secondary);
``aligned`` gives the shorter one a ``t_hold`` so both transfer at the same
instant and are read out together. ``t_store`` adds storage time before the
first row: the wait of row ``r`` of a frame is ``t_pre + r t_row``.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..readout_timing import ROW_FRACTIONS

_FRACTION = dict(ROW_FRACTIONS)

@dataclass(frozen=True)
class GsTiming:
    t_exp: float
    t_row: float
    rows: int = 1
    t_reset: float = 1e-6
    t_tg: float = 0.5e-6
    t_gap: float = 0.3e-6
    edge: float = 10e-9
    t_pre: float = 0.3e-6  # from end of transfer to the first row
    t_hold: float = 0.0    # EC held on after t_reset: the exposure starts later
    t_store: float = 0.0   # extra storage on FD before the first row is read
    ec_hold: bool = False  # EC resets the PD again during storage
    #: ((phase, s from the row's start), ...) of the row read; a phase not given is its
    #: fraction of ``t_row`` (``readout_timing.ROW_FRACTIONS``)
    phases: tuple = ()

    @property
    def precharged(self) -> bool:
        return any(k == "pre_on" for k, _ in self.phases)

    def phase(self, name: str) -> float:
        """Time of row phase ``name`` (``s1_off``, ...) from the row's start (s)."""
        for k, v in self.phases:
            if k == name:
                return v
        return _FRACTION[name] * self.t_row

    @property
    def t_start(self) -> float:
        """EC opens: the start of exposure."""
        return self.t_reset + self.t_hold

    @property
    def t_tx(self) -> float:
        """TG opens: the end of exposure."""
        return self.t_start + self.t_exp

    @property
    def t_read(self) -> float:
        return self.t_tx + self.t_pre + self.t_store

    def t_wait(self, r: int) -> float:
        """Time the charge of row ``r`` waits on FD from the transfer to its signal sample."""
        return self.t_signal(r) - self.t_tx

    def row(self, r: int) -> float:
        return self.t_read + r * self.t_row

    def _window(self, r: int, on: str, off: str):
        t0 = self.row(r)
        return t0 + self.phase(on), t0 + self.phase(off)

    def s1_window(self, r: int):
        return self._window(r, "s1_on", "s1_off")

    def rst_window(self, r: int):
        return self._window(r, "rst_on", "rst_off")

    def s2_window(self, r: int):
        return self._window(r, "s2_on", "s2_off")

    def t_signal(self, r: int) -> float:
        """Instant the signal level is taken (end of S1)."""
        return self.s1_window(r)[1]

    def t_reset_level(self, r: int) -> float:
        """Instant the reset level is taken (end of S2)."""
        return self.s2_window(r)[1]

    def row_end(self, r: int) -> float:
        """End of row ``r``'s read: the next row's start, or later when RS (edge included)
        stays on longer (a long-S1 reference read, ``chip.settling``)."""
        return max(self.row(r + 1), self.row(r) + self.phase("rs_off") + self.edge)

    @property
    def t_stop(self) -> float:
        return self.row_end(self.rows - 1) + 0.05 * self.t_row

    # switch intervals ------------------------------------------------------
    def ec(self):
        on = [(0.0, self.t_start)]
        if self.ec_hold:
            on.append((self.t_tx + self.t_gap, self.t_stop))
        return on

    def tg(self):
        return [(self.t_tx - self.t_tg, self.t_tx)]

    def rst(self, r: int):
        return [(0.0, self.t_tx - self.t_tg - self.t_gap), self.rst_window(r)]

    def rs(self, r: int):
        return [self._window(r, "rs_on", "rs_off")]

    def row_list(self, rows=None) -> list:
        """Rows to clock: all (None), the first ``rows`` (an int), or the given row indices."""
        if rows is None:
            return list(range(self.rows))
        return list(range(rows)) if isinstance(rows, int) else list(rows)

    def s1(self, rows=None):
        return [self.s1_window(r) for r in self.row_list(rows)]

    def s2(self, rows=None):
        return [self.s2_window(r) for r in self.row_list(rows)]

    def pre(self, rows=None):
        """Column precharge windows (none unless the design sets ``pre_on`` / ``pre_off``)."""
        return [self._window(r, "pre_on", "pre_off") for r in self.row_list(rows)] if self.precharged else []


def timings(design, t_exp: float, rows: int = 1, t_exp_secondary: float | None = None,
            t_store: float = 0.0, ec_hold: bool | None = None) -> dict:
    """Per-array GS timing from the design's ``[<array>.timing]`` keys, each array with its
    own row time.

    ``t_exp`` is the primary exposure; the secondary's is ``t_exp_secondary``
    (default: the same window). The shorter exposure starts later (EC held) so
    both arrays transfer together; ``t_store`` adds storage before the first row
    (to the design's ``t_store``). ``ec_hold``: the caller's default when the design
    does not set ``timing.ec_hold`` (benches: off).
    """
    exp = {"primary": t_exp, "secondary": t_exp if t_exp_secondary is None else t_exp_secondary}
    keys = {k: getattr(design, k).timing for k in exp}
    for k, t in exp.items():
        keys[k].check_exposure(t, k, design.source, "t_exp", t)
    # the arrays transfer together: the one whose exposure ends first holds EC longer
    base = {k: keys[k].t_reset + keys[k].t_hold for k in exp}
    if len(set(base.values())) == 1:
        late = {k: max(exp.values()) - exp[k] for k in exp}
    else:
        late = {k: max(base[j] + exp[j] for j in exp) - (base[k] + exp[k]) for k in exp}
    out = {}
    for k, key in keys.items():
        hold = ec_hold if key.ec_hold is None else key.ec_hold
        out[k] = GsTiming(exp[k], 1.0 / getattr(design, k).f_read, rows=rows, t_reset=key.t_reset,
                          t_tg=key.t_tg, t_gap=key.t_gap, edge=key.edge, t_pre=key.t_pre,
                          t_hold=key.t_hold + late[k], t_store=key.t_store + t_store,
                          ec_hold=bool(hold), phases=_given_phases(key))
    return out


def _given_phases(key) -> tuple:
    names = [k for k, _ in ROW_FRACTIONS] + ["pre_on", "pre_off"]
    return tuple((k, getattr(key, k)) for k in names if getattr(key, k) is not None)
