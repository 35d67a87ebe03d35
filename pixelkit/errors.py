"""Errors a user can act on. The CLI prints them as one line and exits non-zero."""
from __future__ import annotations


class PixelkitError(Exception):
    """A user-facing failure: the message says what is wrong and what is allowed."""


class ConfigError(PixelkitError):
    """A field of a design, technology or data file is missing or not allowed."""

    def __init__(self, source: str, field: str, value, allowed: str):
        self.source, self.field, self.value, self.allowed = source, field, value, allowed
        where = f"{source}: " if source else ""
        shown = "(missing)" if value is _MISSING else repr(value)
        super().__init__(f"{where}{field} = {shown}: expected {allowed}")


class _Missing:
    def __repr__(self):
        return "(missing)"


_MISSING = _Missing()
MISSING = _MISSING


class SimulationError(PixelkitError):
    """ngspice failed: names the deck, the analysis and ngspice's own message."""

    def __init__(self, deck: str, analysis: str, message: str):
        self.deck, self.analysis, self.message = deck, analysis, message
        super().__init__(f"simulation of '{deck}' ({analysis}) failed: {message}")


class InfeasibleError(PixelkitError):
    """A sizing problem has no solution; names the constraints in conflict."""

    def __init__(self, message: str, conflicts: list[str]):
        self.conflicts = conflicts
        super().__init__(f"{message}: constraints in conflict: {', '.join(conflicts)}")
