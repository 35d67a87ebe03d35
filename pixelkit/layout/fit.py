"""Can the design be drawn? The kit's rules and a dry run of the generators, nothing written.

A design that cannot be drawn is a *layout* error: ``pixelkit layout`` refuses it (exit 2,
the rule and the field named); the circuit-only commands run it with a warning, so a
designer can ask "what if" before fixing the floor plan.
"""
from __future__ import annotations

from .rules import RuleError, check


def drawing_problem(design, full: bool = False) -> RuleError | None:
    """The first rule the design breaks when drawn, or None. Quick (every command): the kit's
    rules and the devices placed in each cell; ``full``: every cell drawn and routed."""
    try:
        check(design)
        if full:
            from .library import build_cells
            build_cells(design)
        else:
            _place(design)
    except RuleError as exc:
        return exc
    return None


def _place(design) -> None:
    from .columns import column_cell
    from .dual import plan
    from .pixel import subpixel
    from .techview import LayoutTech
    lt = LayoutTech(design.tech)
    dp = plan(design, lt)
    for p in (dp.primary, dp.secondary):
        subpixel(design, lt, p, place_only=True)
    for kind, p in (("primary", dp.primary), ("secondary", dp.secondary)):
        x = p.col_x
        column_cell(design, lt, kind, p.pitch, {"col": x, "out": x - 660, "nbias": x - 1320}, [], "top",
                    place_only=True)


#: the design field that sizes each cell (named when a cell offers no room for its devices or nets)
CELL_FIELD = {"PRIMARY": "primary.pitch", "SECONDARY": "secondary.pitch", "COLUMN_P": "primary.pitch",
              "COLUMN_S": "secondary.pitch", "DUALPIX": "primary.pitch", "DUALPIX_COL": "primary.pitch",
              "AFE_P": "primary.pitch", "AFE_S": "secondary.pitch", "READOUT_P": "primary.pitch",
              "READOUT_S": "secondary.pitch"}


def as_config_error(design, exc: RuleError):
    """The rule error as the design-file error a user acts on (field, value as written)."""
    from ..errors import ConfigError
    from ..schema import as_written
    field, value = exc.field, exc.value
    if not field:
        field = CELL_FIELD.get(exc.place.split()[0], "primary.pitch")
        value = getattr(design, field.split(".")[0]).pitch
    return ConfigError(design.source, field, as_written(design.raw, field, value),
                       f"a value that keeps layout rule {exc.rule} in the {exc.place} ({exc.detail})")
