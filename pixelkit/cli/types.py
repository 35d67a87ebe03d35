"""Option types of the command line."""
from __future__ import annotations

import math

import click


class FiniteRange(click.FloatRange):
    """click's FloatRange that also refuses NaN and infinities (NaN passes FloatRange's comparisons)."""

    name = "float range"

    def convert(self, value, param, ctx):
        v = super().convert(value, param, ctx)
        if not math.isfinite(v):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return v
