"""Typed simulation results: a time axis, named vectors and metadata."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def vector_key(name: str) -> str:
    """Canonical vector name: ``v(node)`` / ``i(source)``, lower case, hierarchy with '.'."""
    n = name.lower()
    if n == "time" or "(" in n:
        return n
    if n.endswith("#branch"):
        return f"i({n[:-7]})"
    return f"v({n})"


@dataclass(frozen=True)
class Result:
    """One analysis: ``time`` (s; empty for .op), ``vectors`` by canonical name, ``meta``.

    ``meta`` holds: backend, options, ngspice version, wall time (s), deck title and
    hash, cached (bool), and ``retried`` when the retry policy loosened options.
    """
    time: np.ndarray
    vectors: dict
    meta: dict = field(default_factory=dict)

    def __getitem__(self, name: str) -> np.ndarray:
        key = vector_key(name)
        if key not in self.vectors:
            near = ", ".join(sorted(self.vectors)[:12])
            raise KeyError(f"no vector {key!r} in the result of {self.meta.get('title', '?')} "
                           f"(have: {near}...)")
        return self.vectors[key]

    def v(self, node: str) -> np.ndarray:
        return self[f"v({node})"]

    def at(self, name: str, t) -> np.ndarray:
        """Value of vector ``name`` at time(s) ``t`` (linear interpolation)."""
        return np.interp(t, self.time, self[name])

    def names(self) -> list[str]:
        return sorted(self.vectors)
