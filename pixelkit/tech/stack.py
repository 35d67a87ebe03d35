"""The process stack of a technology: what extraction (``layout.pex``) computes parasitics from.

``[stack]`` in a technology file::

    [stack]
    source = "..."                      # where the numbers come from (quoted in the docs and reports)
    dielectric_k = 4.0                  # relative permittivity between the conductors
    halo = "8 um"                       # farthest lateral coupling counted
    [stack.layers]                      # conductors above the substrate, by the layer names of [layers]
    poly = { z = "0.32 um", thickness = "0.2 um", sheet = "7.3 Ohm", via_below = "5.9 Ohm" }
    metal1 = { z = "1.23 um", thickness = "0.55 um", sheet = "0.09 Ohm", via_below = "6.3 Ohm" }

``z`` is the conductor's bottom above the substrate surface, ``sheet`` its sheet resistance
(Ohm per square), ``via_below`` the resistance of one cut to the conductor below; ``device_below =
true`` marks a capacitor's top plate (the MIM's), whose coupling to the conductor under it is the
capacitor itself (a device of the netlist), not wiring. Diffusions
and wells are conductors at the substrate surface (z = 0). A technology without ``[stack]``
has no post-layout view: :func:`require_stack` names what is missing.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..errors import MISSING, ConfigError
from ..units import quantity

EPS0 = 8.8541878128e-12


@dataclass(frozen=True)
class Conductor:
    name: str
    z: float            # bottom above the substrate surface (m)
    thickness: float    # m
    sheet: float        # Ohm per square
    via_below: float    # Ohm per cut to the conductor below
    device_below: bool = False   # a capacitor's top plate: what lies under it is the device (no wiring C)

    @property
    def top(self) -> float:
        return self.z + self.thickness


@dataclass(frozen=True)
class Stack:
    source: str
    dielectric_k: float
    halo: float
    conductors: tuple   # Conductor, bottom to top

    @property
    def eps(self) -> float:
        return EPS0 * self.dielectric_k

    def conductor(self, name: str) -> Conductor:
        return next(c for c in self.conductors if c.name == name)

    def names(self) -> tuple:
        return tuple(c.name for c in self.conductors)


_KEYS = {"z": "m", "thickness": "m", "sheet": "Ohm", "via_below": "Ohm"}
_FLAGS = ("device_below",)


def parse_stack(raw, source: str, layer_names) -> Stack | None:
    """The ``[stack]`` table (None when the technology has none)."""
    if raw is None:
        return None
    if not isinstance(raw, dict):
        raise ConfigError(source, "stack", raw, "a table (source, dielectric_k, halo, [stack.layers])")
    extra = set(raw) - {"source", "dielectric_k", "halo", "layers"}
    if extra:
        bad = sorted(extra)[0]
        raise ConfigError(source, f"stack.{bad}", raw[bad], "one of source, dielectric_k, halo, layers")
    src = raw.get("source", MISSING)
    if not isinstance(src, str) or not src.strip():
        raise ConfigError(source, "stack.source", src, "where the stack's numbers come from (a citation)")
    k = quantity(raw.get("dielectric_k", MISSING), "1", "stack.dielectric_k", source)
    if not 1.0 <= k <= 20.0:
        raise ConfigError(source, "stack.dielectric_k", raw.get("dielectric_k"), "a relative permittivity 1 - 20")
    halo = quantity(raw.get("halo", MISSING), "m", "stack.halo", source)
    if not 0 < halo <= 100e-6:
        raise ConfigError(source, "stack.halo", raw.get("halo"), "a distance above 0, at most 100 um")
    layers = raw.get("layers", MISSING)
    if not isinstance(layers, dict) or not layers:
        raise ConfigError(source, "stack.layers", layers, "a table of conductors by layer name")
    out = []
    for name, v in layers.items():
        where = f"stack.layers.{name}"
        if name not in layer_names:
            raise ConfigError(source, where, name, f"a layer of the [layers] table ({', '.join(sorted(layer_names))})")
        if not isinstance(v, dict) or not set(_KEYS) <= set(v) <= set(_KEYS) | set(_FLAGS) \
                or not all(isinstance(v.get(f, False), bool) for f in _FLAGS):
            raise ConfigError(source, where, v, "{ z, thickness, sheet, via_below } with units (and device_below = "
                              "true for a capacitor's top plate)")
        vals = {key: quantity(v[key], dim, f"{where}.{key}", source) for key, dim in _KEYS.items()}
        for key, hi in (("z", 1e-4), ("thickness", 1e-4), ("sheet", 1e6), ("via_below", 1e6)):
            lo_ok = vals[key] > 0 if key in ("z", "thickness") else vals[key] >= 0
            if not (lo_ok and vals[key] <= hi):
                raise ConfigError(source, f"{where}.{key}", v[key], "a positive value" if key in ("z", "thickness")
                                  else "a value >= 0")
        out.append(Conductor(name, **vals, device_below=v.get("device_below", False)))
    out.sort(key=lambda c: c.z)
    for a, b in zip(out, out[1:]):
        if b.z < a.top:
            raise ConfigError(source, f"stack.layers.{b.name}.z", f"{b.z * 1e6:g} um",
                              f"a height above the top of {a.name} ({a.top * 1e6:g} um): conductors do not overlap")
    return Stack(src.strip(), k, halo, tuple(out))


def require_stack(tech, what: str = "--post-layout") -> Stack:
    """The technology's stack, or a clear error naming what is missing for ``what``."""
    st = getattr(tech, "stack", None)
    if st is None:
        raise ConfigError(tech.source, "stack", MISSING,
                          f"a [stack] table in technology {tech.name} (the conductors' heights, thicknesses, sheet "
                          f"resistances and the dielectric) for {what}: extraction needs it; without it there is "
                          "no post-layout view (the schematic is not run in its place). Add one as the technology "
                          "file reference says (docs/technology-file.md, section [stack]; the gf180mcu technology "
                          "has one), or use a design on a technology that has it (designs/dual_pixel_gf180.toml)")
    return st
