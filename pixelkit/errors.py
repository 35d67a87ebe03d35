"""Errors a user can act on, and the exit status of each kind.

The CLI prints them as one line (or one JSON object with ``--json``) and exits
with the class's ``exit_status``:

====  ==========================================================
0     success
1     a regression / comparison found a difference (:class:`RegressionFound`)
2     user error: a bad design file, option or data file (:class:`PixelkitError`,
      :class:`ConfigError`, :class:`InfeasibleError`, click usage errors)
3     internal fault of the kit (any other exception: a bug, please report it)
4     a simulation failed (:class:`SimulationError`: ngspice did not converge)
5     nothing failed, but something asked was not measured: a spec not run at any condition or
      not measured at some of its conditions, a check skipped (:func:`verdict_exit`)
130   interrupted (Ctrl-C)
====  ==========================================================
"""
from __future__ import annotations

EXIT_OK, EXIT_REGRESSION, EXIT_USER, EXIT_INTERNAL, EXIT_SIMULATION, EXIT_INTERRUPTED = 0, 1, 2, 3, 4, 130
EXIT_NOT_MEASURED = 5

#: the one status of a sign-off item that is a pass; "fail" fails; every other status ("not run",
#: "not measured", "skipped", or one this rule has never heard of) means it was not measured
PASS, FAIL = "pass", "fail"


def verdict_exit(statuses, simulation_failed: bool = False) -> int:
    """The exit status of a verdict over items with these statuses (the team rule, issue 44):
    1 when any item fails (it takes precedence), else 4 when a simulation failed, else 5 when any
    item was not measured (not run anywhere, not at some of its conditions, skipped), else 0.
    Zero items is not a pass: nothing asked was measured (5). ``verify``, ``report``, ``close``,
    ``lightmap`` and the layout sign-off all decide their status here."""
    statuses = [str(s).lower() for s in statuses]
    if FAIL in statuses:
        return EXIT_REGRESSION
    if simulation_failed:
        return EXIT_SIMULATION
    if not statuses or any(s != PASS for s in statuses):
        return EXIT_NOT_MEASURED
    return EXIT_OK


class PixelkitError(Exception):
    """A user-facing failure: the message says what is wrong and what is allowed."""

    exit_status = EXIT_USER

    def __str__(self) -> str:
        """Always one line: a line break or control character from a file name or a value
        (``\n``, ``\x85``, U+2028 ...) is shown escaped (issue 9)."""
        text = super().__str__()
        return text if text.isprintable() else "".join(c if c.isprintable() else ascii(c)[1:-1] for c in text)

    def details(self) -> dict:
        """Structured fields of the error for ``--json`` (besides the message)."""
        return {}


class ConfigError(PixelkitError):
    """A field of a design, technology or data file is missing or not allowed."""

    def __init__(self, source: str, field: str, value, allowed: str):
        self.source, self.field, self.value, self.allowed = source, field, value, allowed
        where = f"{source}: " if source else ""
        shown = "(missing)" if value is _MISSING else repr(value)
        super().__init__(f"{where}{field} = {shown}: expected {allowed}")

    def details(self) -> dict:
        shown = None if self.value is _MISSING else self.value
        if isinstance(shown, float) and shown != shown or shown in (float("inf"), float("-inf")):
            shown = repr(shown)  # NaN / Infinity are not JSON
        return {"source": self.source, "field": self.field, "value": shown, "allowed": self.allowed}


class _Missing:
    def __repr__(self):
        return "(missing)"


_MISSING = _Missing()
MISSING = _MISSING


class SimulationError(PixelkitError):
    """ngspice failed: names the deck, the analysis and ngspice's own message.

    When the engine kept the failed deck, ``folder`` holds ``deck.cir`` and
    ``ngspice.log``; ``what`` says the bench and operating point in the user's
    terms, ``tried`` the option sets that were run, ``hints`` what to change.
    """

    exit_status = EXIT_SIMULATION

    def __init__(self, deck: str, analysis: str, message: str, *, what: str = "", folder=None,
                 tried=(), hints=()):
        self.deck, self.analysis, self.message = deck, analysis, message
        self.what, self.folder, self.tried, self.hints = what, folder, list(tried), list(hints)
        text = f"simulation of {what or repr(deck)} ({analysis}) failed: {message}"
        if self.tried:
            text += f"; tried {len(self.tried)} option set(s): " + " | ".join(self.tried)
        if folder:
            text += f"; deck and ngspice log kept in {folder}"
        if self.hints:
            text += "; you can: " + "; ".join(self.hints)
        super().__init__(text)

    def details(self) -> dict:
        return {"deck": self.deck, "what": self.what, "analysis": self.analysis, "message": self.message,
                "folder": None if self.folder is None else str(self.folder), "tried": self.tried,
                "hints": self.hints}


class RegressionFound(PixelkitError):
    """A comparison with a baseline or golden copy found differences (exit status 1)."""

    exit_status = EXIT_REGRESSION


class InfeasibleError(PixelkitError):
    """A sizing problem has no solution; names the constraints in conflict."""

    def __init__(self, message: str, conflicts: list[str]):
        self.conflicts = conflicts
        super().__init__(f"{message}: constraints in conflict: {', '.join(conflicts)}")

    def details(self) -> dict:
        return {"conflicts": list(self.conflicts)}
