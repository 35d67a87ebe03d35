"""The knob space of ``pixelkit close``: scaled coordinates, values as written, designs at a point.

Coordinates: a ``lin`` knob moves in fractions of its span, u = (x - min) / (max - min); a
``log`` knob in its logarithm, u = ln x (a step of 0.01 is 1 % of its value). The trust region
and the tolerance are in these units, so 0.01 is 1 % of a span or of a value.

Every point close simulates is first written as the design file would hold it (the value with
its unit, rounded to the knob's ``step`` or to 6 significant digits) and loaded through the
design loader (``sweep.space.design_with``): the revision close writes is exactly the design it
verified, and a combination of knobs the design file refuses (a timing phase past the next one)
is a ConfigError, never a deck.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from ..units import quantity, si_text
from ..verify.close_table import value_of

def text(x: float, dim: str, unit_required: bool = False, digits: int = 6) -> str:
    """``x`` (SI) as a design file holds it: ``"1.23456 uA"``, ``"0.605 um"``, ``"398.2 V/V"``."""
    if dim == "1":
        return f"{x:.{digits}g}" + (" V/V" if unit_required else "")
    if dim == "m":   # device sizes and distances as a layout shows them
        return f"{x * 1e6:.{digits}g} um"
    return si_text(x, dim, digits)


def written(design, key: str) -> bool:
    """Whether the design's file writes ``key`` (a default the file leaves is not the designer's value: the
    reference's transistor OTA, which revA does not use, has no bias of its own)."""
    raw = getattr(design, "raw", None)
    if raw is None:
        return True
    for part in key.split("."):
        if not isinstance(raw, dict) or part not in raw:
            return False
        raw = raw[part]
    return True


def at_bound(k, x: float) -> str | None:
    """``"min"`` / ``"max"`` when ``x`` sits on that bound of knob ``k``."""
    if abs(x - k.lo) <= 1e-9 * max(abs(k.lo), 1e-30):
        return "min"
    if abs(x - k.hi) <= 1e-9 * max(abs(k.hi), 1e-30):
        return "max"
    return None


@dataclass(frozen=True)
class Space:
    knobs: tuple          # verify.close_table.Knob, bounds in SI

    @property
    def names(self) -> list[str]:
        return [k.name for k in self.knobs]

    @property
    def n(self) -> int:
        return len(self.knobs)

    def to_u(self, x) -> np.ndarray:
        return np.array([math.log(v) if k.log else (v - k.lo) / (k.hi - k.lo) for k, v in zip(self.knobs, x)])

    def to_x(self, u) -> np.ndarray:
        return np.array([math.exp(w) if k.log else k.lo + w * (k.hi - k.lo) for k, w in zip(self.knobs, u)])

    @property
    def u_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        lo = np.array([math.log(k.lo) if k.log else 0.0 for k in self.knobs])
        hi = np.array([math.log(k.hi) if k.log else 1.0 for k in self.knobs])
        return lo, hi

    def start(self, design) -> tuple[np.ndarray, list[str]]:
        """The design's own knob values, each clipped into its bounds, and a note per clipped one."""
        x, notes = [], []
        for k in self.knobs:
            v = value_of(design, k.name) if written(design, k.name) else None
            if v is None:   # absent in the design (its file does not write it: a default is no choice): the middle
                v = math.sqrt(k.lo * k.hi) if k.log else (k.lo + k.hi) / 2
                notes.append(f"{k.name} starts at {self.texts([v], [k])[0]}, the middle of its bounds (the design "
                             "leaves it absent)")
            v = float(v)
            c = min(max(v, k.lo), k.hi)
            if c != v:
                notes.append(f"{k.name} starts at {self.texts([c], [k])[0]}: the design's "
                             f"{text(v, k.dim, k.unit_required)} is outside its bounds")
            x.append(c)
            for key in k.tied:
                w = value_of(design, key) if written(design, key) else None
                if w is None or abs(float(w) - c) > 1e-9 * max(abs(c), 1e-30):
                    notes.append(f"{key} starts at {self.texts([c], [k])[0]}, tied to {k.name}")
        return self.snap(np.array(x)), notes

    def texts(self, x, knobs=None) -> list[str]:
        out = []
        for k, v in zip(knobs or self.knobs, x):
            if k.grid:
                v = round(v / k.grid) * k.grid
                out.append(text(v, k.dim, k.unit_required, digits=12))
            else:
                out.append(text(v, k.dim, k.unit_required))
        return out

    def snap(self, x) -> np.ndarray:
        """``x`` as written (rounded), back in SI, clipped into the bounds."""
        vals = []
        for k, t in zip(self.knobs, self.texts(x)):
            v = quantity(t, k.dim, k.name)
            if v < k.lo or v > k.hi:   # rounding pushed it out: the bound itself, as written
                v = k.lo if v < k.lo else k.hi
                v = quantity(self.texts([v], [k])[0], k.dim, k.name)
            vals.append(v)
        return np.array(vals)

    def overrides(self, x) -> dict:
        """{design key: value as written} of each knob and of the keys it ties (``tied``: the same value)."""
        out = {}
        for k, t in zip(self.knobs, self.texts(x)):
            out[k.name] = t
            out.update({key: t for key in k.tied})
        return out

    def design(self, base, x):
        """The design at knob values ``x`` (SI, already snapped), loaded as a file would be; in the
        post-layout view when ``base`` is in it (the layout drawn and extracted again for these values)."""
        from ..sweep.space import design_with
        return same_view(base, design_with(base, self.overrides(x)))


def same_view(base, d):
    """``d`` in ``base``'s view: post-layout (drawn and extracted again for ``d``'s values) when ``base`` is."""
    pl = getattr(base, "post_layout", None)
    if pl is None:
        return d
    if hasattr(base, "reloaded"):   # a pixel read by role: the 4T's cell
        from ..layout.pixel4t import post_layout_view as role_view
        return role_view(d)
    from ..layout.pex.overlay import post_layout_view
    return post_layout_view(d, pl.afe)


def check_bounds(space: Space, design) -> None:
    """Each knob at each of its bounds (the others as designed, clipped) gives a design the file
    loader and every condition of the grid accept; refused naming the bound otherwise."""
    from ..verify import conditions
    from ..verify.run import suite
    at = suite(design).at
    x0, _ = space.start(design)
    grid = conditions.grid(design)
    for j, k in enumerate(space.knobs):
        for bound, v in (("min", k.lo), ("max", k.hi)):
            x = x0.copy()
            x[j] = v
            x = space.snap(x)
            try:
                d = space.design(design, x)
                for c in grid:
                    at(d, c)
            except ConfigError as exc:
                raise ConfigError(design.source, f"close.knobs.{k.name}.{bound}", getattr(k, bound),
                                  f"a bound at which the design is valid ({exc.field} = {exc.value!r}: expected "
                                  f"{exc.allowed})") from None
