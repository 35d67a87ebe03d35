"""The timing keys of a design file: ``[primary.timing]`` and ``[secondary.timing]``.

Each array has its own global-shutter sequence and its own row read. The keys are
the designer's (``docs/timing-and-settling.md``); their defaults are the kit's
former built-in values, so a design without a ``timing`` table simulates exactly as
before.

Global shutter (durations, s)::

    0 .. t_reset + t_hold      EC on (PD reset) and RST on (FD reset)
    EC opens                   exposure starts
    t_gap before TG on         RST opens (FD released before the transfer)
    t_tg before exposure end   TG on: the global transfer; exposure ends when TG opens
    t_pre + t_store            storage on FD before the first row is read

A row read (times from the row's start, s; absent = the kit's fraction of the row
time 1/f_read, in brackets)::

    rs_on  (0.02)  .. rs_off  (0.98)   RS: the row drives the column
    s1_on  (0.10)  .. s1_off  (0.40)   S1: the signal level is sampled (at s1_off)
    rst_on (0.45)  .. rst_off (0.55)   RST: FD is reset
    s2_on  (0.60)  .. s2_off  (0.90)   S2: the reset level is sampled (at s2_off)

Every control edge takes ``edge``. Checked when the design loads: the phases lie inside
the row in this order, S1 / RST / S2 do not overlap (a phase's falling edge ends before
the next one starts), each phase is longer than an edge, and the row's RS ends before
the next row's starts.
"""
from __future__ import annotations

from dataclasses import dataclass

from .errors import ConfigError
from .schema import as_written, flag, qty
from .units import si_text

#: The row phases in the order they must come, with the kit's fraction of the row time
#: used when a key is absent (the former built-in read).
ROW_FRACTIONS = (("rs_on", 0.02), ("s1_on", 0.1), ("s1_off", 0.4), ("rst_on", 0.45), ("rst_off", 0.55),
                 ("s2_on", 0.6), ("s2_off", 0.9), ("rs_off", 0.98))
#: (on, off) key pairs of the pulses inside a row.
PULSES = (("rs_on", "rs_off"), ("s1_on", "s1_off"), ("rst_on", "rst_off"), ("s2_on", "s2_off"))

_ROW = (0.0, 1.0)     # plausible: a row phase at most 1 s into its row


def _row_key(frac: float, what: str):
    return qty("s", None, ge=0, le=1.0, plausible=_ROW,
               doc=f"when {what} (from the row's start); absent = {frac:g} / f_read")


@dataclass(frozen=True)
class Timing:
    """Global-shutter sequence and row read of one array (the defaults are the kit's former built-in timing)."""
    t_reset: float = qty("s", 1e-6, gt=0, plausible=(1e-9, 1.0),
                         doc="EC and RST on at the frame's start: PD and FD reset")
    t_hold: float = qty("s", 0.0, ge=0, plausible=(0.0, 10.0),
                        doc="EC held on after the reset (the exposure starts later); the kit adds what aligns "
                            "the two arrays' transfers")
    t_tg: float = qty("s", 0.5e-6, gt=0, plausible=(1e-9, 1.0),
                      doc="TG pulse: the global transfer, ending the exposure")
    t_gap: float = qty("s", 0.3e-6, gt=0, plausible=(1e-9, 1.0),
                       doc="from RST opening to TG turning on: FD is released just before the transfer")
    t_pre: float = qty("s", 0.3e-6, ge=0, plausible=(0.0, 1.0),
                       doc="pre-read: from the end of the transfer to the first row")
    t_store: float = qty("s", 0.0, ge=0, plausible=(0.0, 10.0),
                         doc="extra storage on FD before the first row (added to t_pre)")
    edge: float = qty("s", 10e-9, gt=0, plausible=(1e-12, 1e-3),
                      doc="rise and fall time of every control edge")
    ec_hold: bool | None = flag(None, doc="EC holds the PD in reset during storage (anti-blooming); absent = on "
                                          "in array frames, off in the single-pixel benches")
    rs_on: float | None = _row_key(0.02, "RS (row select) closes")
    s1_on: float | None = _row_key(0.1, "S1 (signal sample) closes")
    s1_off: float | None = _row_key(0.4, "S1 opens (the signal level is taken)")
    rst_on: float | None = _row_key(0.45, "RST (FD reset) closes")
    rst_off: float | None = _row_key(0.55, "RST opens")
    s2_on: float | None = _row_key(0.6, "S2 (reset sample) closes")
    s2_off: float | None = _row_key(0.9, "S2 opens (the reset level is taken)")
    rs_off: float | None = _row_key(0.98, "RS opens")
    pre_on: float | None = qty("s", None, ge=0, le=1.0, plausible=_ROW,
                               doc="column precharge: a switch pulls the column line (and C11 through S1X) to "
                                   "ground from pre_on to pre_off, inside S1, so the source follower always "
                                   "settles upwards; absent = no precharge")
    pre_off: float | None = qty("s", None, ge=0, le=1.0, plausible=_ROW, doc="end of the column precharge")

    def row(self, t_row: float) -> dict:
        """Every row phase in s from the row's start, the absent ones at their fraction of ``t_row``."""
        return {k: (frac * t_row if getattr(self, k) is None else getattr(self, k)) for k, frac in ROW_FRACTIONS}

    def check(self, t_row: float, nonoverlap: float, where: str, source: str, raw) -> None:
        """The row read fits ``t_row`` in order; ``raw``: the subpixel's table as written."""
        ph = self.row(t_row)

        def refuse(key, allowed):
            value = ph[key] if key in ph else getattr(self, key)
            shown = as_written(raw, f"timing.{key}", si_text(value, "s"))
            raise ConfigError(source, f"{where}.timing.{key}", shown, allowed + _row_note(self, key, t_row))
        e = self.edge
        for key in ("t_reset", "t_tg", "t_gap"):
            if getattr(self, key) <= e:
                raise ConfigError(source, f"{where}.timing.{key}", as_written(raw, f"timing.{key}", getattr(self, key)),
                                  f"a phase longer than the edge ({si_text(e, 's')})")
        names = [k for k, _ in ROW_FRACTIONS]
        eps = 1e-9 * t_row    # "1000 ns" in a 1 MHz row is inside it, whatever the last bit says
        for key in names:
            if ph[key] > t_row + eps:
                refuse(key, f"a time inside the row (at most 1/f_read = {si_text(t_row, 's')})")
        for prev, key in zip(names, names[1:]):
            need = e if prev != "rs_on" else 0.0   # S1 may close while RS rises
            pulse = (prev, key) in PULSES
            if ph[key] - ph[prev] > need + eps or (not pulse and ph[key] - ph[prev] >= need - eps):
                continue
            what = ("a pulse longer than its edge" if pulse else
                    "phases in the order RS, S1, RST, S2 without overlap")
            plus = " + one edge" if need else ""
            if getattr(self, key) is None and getattr(self, prev) is None:   # both at their fractions
                raise ConfigError(source, f"{where}.timing.edge", as_written(raw, "timing.edge", si_text(e, "s")),
                                  f"an edge shorter than every phase and gap of the row ({prev} to {key}: "
                                  f"{si_text(ph[key] - ph[prev], 's')} at f_read = {si_text(1 / t_row, 'Hz')})")
            if getattr(self, key) is None:   # blame the key given
                refuse(prev, f"a time {'before' if pulse else 'at most'} {si_text(ph[key] - need, 's')} "
                             f"({key} {si_text(ph[key], 's')}{plus.replace('+', '-')}): {what}")
            refuse(key, f"a time {'after' if pulse else 'at least'} {si_text(ph[prev] + need, 's')} "
                        f"({prev} {si_text(ph[prev], 's')}{plus}): {what}")
        self._check_precharge(ph, e, eps, refuse)
        if ph["s1_off"] - ph["s1_on"] <= nonoverlap + e + eps:
            refuse("s1_off", f"an S1 longer than the AFE's non-overlap plus one edge "
                             f"({si_text(nonoverlap + e, 's')} after s1_on)")
        if ph["rs_off"] + e > t_row + ph["rs_on"] + eps:
            refuse("rs_off", f"at most {si_text(t_row + ph['rs_on'] - e, 's')}: RS opens (edge included) before "
                             f"the next row's RS closes (row time 1/f_read = {si_text(t_row, 's')})")

    def _check_precharge(self, ph, e, eps, refuse):
        given = [k for k in ("pre_on", "pre_off") if getattr(self, k) is not None]
        if not given:
            return
        if len(given) == 1:
            other = "pre_off" if given[0] == "pre_on" else "pre_on"
            refuse(given[0], f"a value together with {other} (a precharge has a start and an end)")
        on, off = self.pre_on, self.pre_off
        if on < ph["s1_on"] - eps:
            refuse("pre_on", f"a time at least s1_on ({si_text(ph['s1_on'], 's')}): C11 is precharged through S1X")
        if off - on <= e + eps:
            refuse("pre_off", f"a time more than one edge after pre_on ({si_text(on, 's')})")
        if off + e > ph["s1_off"] + eps:
            refuse("pre_off", f"a time at most {si_text(ph['s1_off'] - e, 's')}: the precharge ends (edge "
                              f"included) before S1 opens ({si_text(ph['s1_off'], 's')})")

    def check_exposure(self, t_exp: float, where: str, source: str, what: str, shown) -> None:
        """TG and the FD release fit inside an exposure of ``t_exp`` (``what``: the key giving it)."""
        if self.t_tg + self.t_gap >= t_exp:
            raise ConfigError(source, what, shown,
                              f"an exposure longer than {where}.timing.t_tg + t_gap "
                              f"({si_text(self.t_tg + self.t_gap, 's')}): FD is released and the "
                              "transfer starts inside the exposure")


def _row_note(t: Timing, key: str, t_row: float) -> str:
    if getattr(t, key) is None and key in dict(ROW_FRACTIONS):
        return f" (absent: {dict(ROW_FRACTIONS)[key]:g} / f_read; set the other row keys to fit)"
    return ""
