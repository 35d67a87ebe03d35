"""Input checks: how close each design and technology quantity sits to the edge of its
plausibility range, and what the model-library guard found (issue 9)."""
from __future__ import annotations

import dataclasses
import math

from . import Section, Table

TITLE = "Input checks: plausibility and model library"
#: A value in the outer 5 % of its range (log scale where the range spans decades) is "near the edge".
NEAR = 0.05


def quantities(obj, prefix: str = ""):
    """(dotted field, SI value, dimension, (lo, hi)) of every loaded field with a plausibility range."""
    for f in dataclasses.fields(obj):
        meta = f.metadata
        value = getattr(obj, f.name, None)
        if meta.get("kind") == "table" and value is not None:
            yield from quantities(value, f"{prefix}{f.name}.")
        elif meta.get("plausible") is not None and isinstance(value, (int, float)):
            yield f"{prefix}{f.name}", float(value), meta.get("dim", "1"), meta["plausible"]


def position(x: float, lo: float, hi: float) -> float:
    """Where ``x`` sits in [lo, hi]: 0 at the low edge, 1 at the high edge; on a log scale
    when the range spans a decade or more (capacitances, currents), else linear."""
    if lo > 0 and x > 0 and hi / lo >= 10:
        return math.log(x / lo) / math.log(hi / lo)
    return (x - lo) / (hi - lo)


def build(ctx) -> Section:
    from ...units import si_text
    d = ctx.design
    rows = []
    for where, obj in (("design", d), ("technology", d.tech)):
        for name, x, dim, (lo, hi) in quantities(obj):
            pos = position(x, lo, hi)
            rows.append([f"{where}: {name}", si_text(x, dim), si_text(lo, dim) if lo else "0", si_text(hi, dim),
                         round(pos, 3), "near the edge" if lo > 0 and pos < NEAR or pos > 1 - NEAR else ""])
    rows.sort(key=lambda r: (not r[5], min(r[4], 1 - r[4])))
    near = [r[0] for r in rows if r[5]]
    incs = d.tech.models.includes(d.corner or None)
    text = [f"Every quantity of the design and its technology is inside its plausibility range (the loader "
            f"refuses anything else); {len(rows)} quantities checked, {len(near)} in the outer {NEAR:.0%} of "
            "their range (log scale where it spans decades; listed first). A value near an edge is legal "
            "but worth a second look.",
            f"Model library of {d.tech.name}: {len(incs)} include(s) from {d.tech.models.folder.name}/; no "
            ".control block in them or in the files they include (a model library is executable code: "
            "the kit refuses one that would run simulator commands, docs/security.md). "
            "Decks name the files through the kit's models/ link; no user path is written into a deck."]
    table = Table("input_margins", "Quantities by their position in the plausibility range",
                  ["field", "value", "plausible from", "plausible to", "position (0 = low, 1 = high)", "note"],
                  rows)
    return Section(TITLE, text=text, tables=[table], data={"near_edge": near})
