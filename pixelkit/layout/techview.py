"""The technology as the generators see it: rules by name in whole nm on the grid.

``LayoutTech(tech).nm("poly.extension.active")`` is the rule rounded *up* to the grid
(a minimum stays a minimum); ``space(layer)`` is the layer's spacing rule (``optional=True``:
None for a layer without one - markers, implants the generators keep apart by construction).
"""
from __future__ import annotations

import math
from functools import cached_property

from .rules import RuleError


class LayoutTech:
    def __init__(self, tech):
        self.tech = tech
        self.memo: dict = {}          # derived values (pad sides ...) computed once per technology view

    @cached_property
    def grid(self) -> int:
        return max(1, round(self.tech.rules.grid * 1e9))

    def snap_up(self, x: float) -> int:
        """``x`` nm rounded up to the grid."""
        g = self.grid
        return int(math.ceil(round(x, 6) / g - 1e-9)) * g

    def snap(self, x: float) -> int:
        g = self.grid
        return int(round(x / g)) * g

    def size_nm(self, value_m: float, field: str, place: str, rule: str = "", low: int = 0,
                low_rule: str = "") -> int:
        """A device size of the design in nm: refused (naming ``field``) off the drawing grid or
        under the rule ``rule`` (or ``low`` nm, ``low_rule``)."""
        nm = value_m * 1e9
        if abs(nm - round(nm / self.grid) * self.grid) > 1e-3:
            raise RuleError("grid", place, f"{value_m * 1e6:g} um is not on the {self.grid:g} nm drawing grid",
                            field, value_m)
        lo, name = (self.nm(rule), rule) if rule else (low, low_rule)
        if round(nm) < lo:
            raise RuleError(name, place, f"{value_m * 1e6:g} um < {lo / 1000:g} um", field, value_m)
        return self.snap(nm)

    def nm(self, key: str) -> int:
        v = self.memo.get(key)
        if v is None:
            v = self.memo[key] = self.snap_up(self.tech.rule(key).value * 1e9)
        return v

    def area(self, key: str) -> float:
        """An area rule in nm^2."""
        return self.tech.rule(key).value * 1e18

    def cite(self, key: str) -> str:
        r = self.tech.rule(key)
        return f"{key} = {r.value * 1e6:g} um{r.cite()}"

    def has(self, key: str) -> bool:
        return key in self.tech.layout.rules

    def space(self, layer: str, optional: bool = False):
        """The layer's spacing rule in nm. A generator that computes with it needs it: a missing
        rule is the technology's error naming ``rules.<layer>.space`` (exit 2); ``optional``: None
        for a layer without one (markers, implants kept apart by construction)."""
        key = f"{layer}.space"
        if optional and not self.has(key):
            return None
        return self.nm(key)

    def width(self, layer: str) -> int:
        return self.nm(f"{layer}.width")

    def cut(self, via: str) -> int:
        return self.nm(f"{via}.size")

    def enclosure(self, outer: str, inner: str) -> int:
        return self.nm(f"{outer}.enclosure.{inner}")

    def pad(self, metal: str, via: str) -> int:
        """Side of a square ``metal`` pad over one ``via`` cut."""
        return self.cut(via) + 2 * self.enclosure(metal, via)

    def min_side(self, layer: str, side: int) -> int:
        """The other side a ``side``-wide rectangle needs to meet the layer's area rule."""
        key = f"{layer}.area"
        if not self.has(key):
            return 0
        return self.snap_up(self.area(key) / side)
