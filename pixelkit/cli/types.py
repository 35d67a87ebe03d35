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


class FilePath(click.Path):
    """click's Path that refuses a NUL character as a usage error (exit 2): click stats the path,
    and every os call raises ValueError on a NUL, which was an internal error (issue 44)."""

    def convert(self, value, param, ctx):
        if isinstance(value, str) and "\0" in value:
            self.fail(f"{ascii(value)} holds a NUL character, which no file name can", param, ctx)
        return super().convert(value, param, ctx)
