"""Simulator options: defaults that keep charge on fF nodes accurate, and the retry policy.

Defaults (measured with ngspice 39 on an 8x8 array + SC AFE):
- ``gmin = 1e-15``: the default 1e-12 S across every junction drains a floating
  pixel node (2.7 V -> 0 V in 10 ms); 1e-15 leaves 20 mV. Integration-time
  simulations need it.
- ``chgtol = 1e-18`` and ``reltol = 1e-5``: the default CHGTOL (1e-14 C) is
  larger than the charge on a fF node. Those measurements found 1e-16 / 1e-4 enough
  for 0.09 mV on an SC output, but on the pixel's 5 % point (a ~19 mV secondary
  signal) 1e-16 / 1e-4 left 1.5 mV of error and a signal-vs-current curve that
  wandered by +-5 %; 1e-18 / 1e-5 made it linear to 0.1 % for +14 % run time
  (measured on the dual-pixel bench, docs/engine.md).
- ``abstol = 1e-14``: photocurrents are pA; the default 1 pA is their size.
- ``method = gear``: damps the trapezoidal ringing after switch edges (+2 %).
"""
from __future__ import annotations

DEFAULTS = (("gmin", 1e-15), ("chgtol", 1e-18), ("reltol", 1e-5), ("abstol", 1e-14),
            ("method", "gear"))

#: What a failed run (no convergence, timestep too small) is retried with, in order.
RETRIES = (
    (("gmin", 1e-15), ("chgtol", 1e-16), ("reltol", 1e-4), ("abstol", 1e-13), ("method", "gear"),
     ("itl4", 100)),
)

FAILURE_MARKERS = ("can't find model", "error", "timestep too small", "simulation(s) aborted", "doanalyses",
                   "singular matrix", "no convergence", "could not find", "unknown model", "fatal", "not found",
                   "unknown subckt", "gmin stepping failed", "source stepping failed", "netlist line no")
#: ngspice's closing line after any error: said last, after the line that names the cause.
_GENERIC = ("fatal error in ngspice", "ngspice exited with status", "circuit not parsed", "simulation(s) aborted",
            "cannot recover", "refused the deck", "interrupted due to error")


def merged(base, override) -> tuple:
    d = dict(base)
    d.update(dict(override))
    return tuple(d.items())


def failure_lines(lines) -> list[str]:
    """The lines of ngspice output that say a run failed (case-insensitive markers), ngspice's own
    first error line first (a line ending in ':', such as 'Netlist line no. 2:', joined with the
    line it introduces) and its generic closing lines ('fatal error in ngspice') last."""
    out = []
    lines = list(lines)
    skip = False
    for k, line in enumerate(lines):
        if skip:
            skip = False
            continue
        low = line.lower()
        if any(m in low for m in FAILURE_MARKERS):
            text = line.strip()
            if low.rstrip().endswith((":", "from line")) and k + 1 < len(lines):
                text = f"{text} {lines[k + 1].strip()}"  # the offending deck line, or the cause
                skip = True
            out.append(text)
    specific = [x for x in out if not any(g in x.lower() for g in _GENERIC)]
    return specific + [x for x in out if x not in specific]
