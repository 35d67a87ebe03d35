"""What every family's design file shares: identity, technology, corner, temperature."""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from ..errors import ConfigError
from ..physics.conversion import rectangle
from ..schema import ident, load, qty, read_toml, text
from ..tech import Technology, load_technology


@dataclass(frozen=True)
class FamilyDesign:
    name: str = ident(doc="design name: the report folder and netlist names (letters, digits and _ only)")
    revision: str = text(doc="chip revision label")
    family: str = text(doc="the pixel family of this file")
    technology: str = text("gf180mcu_3v3", doc="a built-in technology name or a path to a .toml file")
    corner: str = ident("", doc="model corner; empty = the technology's default")
    temperature: float = qty("K", 300.15, gt=0, lt=500, doc="die temperature of every simulation")
    tech: Technology = field(default=None, metadata=dict(kind="skip"))
    source: str = field(default="", metadata=dict(kind="skip"))

    @property
    def corner_name(self) -> str:
        return self.corner or self.tech.models.default_corner


class DrawnPd:
    """Area and perimeter of a table's drawn rectangular photodiode ``pd_width`` x ``pd_height``."""

    @property
    def area(self) -> float:
        return rectangle(self.pd_width, self.pd_height)[0]

    @property
    def perimeter(self) -> float:
        return rectangle(self.pd_width, self.pd_height)[1]


def load_family_design(cls, path: str | Path, raw: dict | None = None):
    """Load and validate a design of family class ``cls``, with its technology; ``raw``: the file's content
    as already read (``sweep.space.design_with``: a design with some keys changed, still at ``path``, so its
    relative paths resolve as in the file). A class with a ``raw`` field keeps the content it was loaded from."""
    import dataclasses
    path = Path(path)
    raw = read_toml(path, "design") if raw is None else raw
    design = load(cls, raw, "", str(path))
    tech = load_technology(design.technology, relative_to=path.parent)
    if design.corner and design.corner not in tech.models.corners:
        raise ConfigError(str(path), "corner", design.corner, f"one of {', '.join(sorted(tech.models.corners))}")
    keep = {"raw": raw} if "raw" in {f.name for f in dataclasses.fields(cls)} else {}
    return replace(design, tech=tech, source=str(path), **keep)
