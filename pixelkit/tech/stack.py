"""The process stack of a technology: what extraction (``layout.pex``) computes parasitics from.

``[stack]`` in a technology file::

    [stack]
    source = "..."                      # where the numbers come from (quoted in the docs and reports)
    dielectric_k = 4.0                  # one relative permittivity everywhere, or the layered dielectrics:
    halo = "8 um"                       # farthest lateral coupling counted
    [[stack.dielectrics]]               # bottom up: each layer's top above the substrate surface and its k;
    name = "sti"                        # the last one has no top (it reaches up without end)
    top = "0.32 um"
    k = 4.0
    [stack.layers]                      # conductors above the substrate, by the layer names of [layers]
    poly = { z = "0.32 um", thickness = "0.2 um", sheet = "7.3 Ohm", via_below = "5.9 Ohm" }
    metal1 = { z = "1.23 um", thickness = "0.55 um", sheet = "0.09 Ohm", via_below = "6.3 Ohm" }

``z`` is the conductor's bottom above the substrate surface, ``sheet`` its sheet resistance
(Ohm per square), ``via_below`` the resistance of one cut to the conductor below; ``device_below =
true`` marks a capacitor's top plate (the MIM's), whose coupling to the conductor under it is the
capacitor itself (a device of the netlist), not wiring. Diffusions
and wells are conductors at the substrate surface (z = 0). A technology without ``[stack]``
has no post-layout view: :func:`require_stack` names what is missing.

With ``[[stack.dielectrics]]`` the permittivity depends on where a field runs (``Stack.eps_gap`` for a
field across heights z0 .. z1, the layers in series; ``eps_band`` along a band, in parallel;
``layout.pex.topface.eps_fringe`` an edge's fringe, its top face's field line by line),
and FastCap2 solves the same layers with their interfaces (``layout/pex/fastcap.py``).
"""
from __future__ import annotations

import functools
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
class Dielectric:
    name: str
    top: float          # its top above the substrate surface (m); inf for the last
    k: float


@dataclass(frozen=True)
class Stack:
    source: str
    dielectric_k: float
    halo: float
    conductors: tuple   # Conductor, bottom to top
    dielectrics: tuple = ()   # Dielectric, bottom to top; () : dielectric_k everywhere

    @property
    def eps(self) -> float:
        """The permittivity of a uniform stack (``dielectric_k``); a layered one's at metal level."""
        return EPS0 * self.dielectric_k

    def _layers(self):
        if not self.dielectrics:
            return [(0.0, float("inf"), self.dielectric_k)]
        out, z0 = [], 0.0
        for d in self.dielectrics:
            out.append((z0, d.top, d.k))
            z0 = d.top
        return out

    def eps_gap(self, z0: float, z1: float) -> float:
        """Effective permittivity of a field across heights z0 .. z1 (the layers in series)."""
        return _eps_gap(self, min(z0, z1), max(z0, z1))

    def eps_band(self, z0: float, z1: float) -> float:
        """Effective permittivity of a field along a band of heights z0 .. z1 (the layers in parallel)."""
        return _eps_band(self, min(z0, z1), max(z0, z1))

    def k_at(self, z: float) -> float:
        return next(k for a, b, k in self._layers() if a <= z < b or b == float("inf"))

    def conductor(self, name: str) -> Conductor:
        return next(c for c in self.conductors if c.name == name)

    def names(self) -> tuple:
        return tuple(c.name for c in self.conductors)


@functools.lru_cache(maxsize=1 << 14)     # the extraction asks the same few heights many times
def _eps_gap(stack: Stack, lo: float, hi: float) -> float:
    if hi <= lo:
        return EPS0 * stack.k_at(lo)
    inv = sum((min(b, hi) - max(a, lo)) / k for a, b, k in stack._layers() if min(b, hi) > max(a, lo))
    return EPS0 * (hi - lo) / inv


@functools.lru_cache(maxsize=1 << 14)
def _eps_band(stack: Stack, lo: float, hi: float) -> float:
    if hi <= lo:
        return EPS0 * stack.k_at(lo)
    return EPS0 * sum((min(b, hi) - max(a, lo)) * k for a, b, k in stack._layers()
                      if min(b, hi) > max(a, lo)) / (hi - lo)


_KEYS = {"z": "m", "thickness": "m", "sheet": "Ohm", "via_below": "Ohm"}
_FLAGS = ("device_below",)


def parse_stack(raw, source: str, layer_names) -> Stack | None:
    """The ``[stack]`` table (None when the technology has none)."""
    if raw is None:
        return None
    if not isinstance(raw, dict):
        raise ConfigError(source, "stack", raw, "a table (source, dielectric_k, halo, [stack.layers])")
    extra = set(raw) - {"source", "dielectric_k", "dielectrics", "halo", "layers"}
    if extra:
        bad = sorted(extra)[0]
        raise ConfigError(source, f"stack.{bad}", raw[bad], "one of source, dielectric_k, dielectrics, halo, layers")
    src = raw.get("source", MISSING)
    if not isinstance(src, str) or not src.strip():
        raise ConfigError(source, "stack.source", src, "where the stack's numbers come from (a citation)")
    dielectrics = _dielectrics(raw.get("dielectrics"), source)
    if dielectrics and "dielectric_k" in raw:
        raise ConfigError(source, "stack.dielectric_k", raw["dielectric_k"], "no dielectric_k beside [[stack.dielectrics]] "
                          "(one permittivity everywhere, or the layers)")
    k = 0.0 if dielectrics else quantity(raw.get("dielectric_k", MISSING), "1", "stack.dielectric_k", source)
    if not dielectrics and not 1.0 <= k <= 20.0:
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
    if dielectrics:     # the permittivity at metal level stands for the stack's in code that takes one
        k = next((d.k for d in dielectrics if d.top > out[0].top), dielectrics[-1].k)
    return Stack(src.strip(), k, halo, tuple(out), dielectrics)


def _dielectrics(raw, source: str) -> tuple:
    """``[[stack.dielectrics]]``: bottom up, each { name, top, k }, the last without a top."""
    if raw is None:
        return ()
    if not isinstance(raw, list) or not raw or not all(isinstance(d, dict) for d in raw):
        raise ConfigError(source, "stack.dielectrics", raw, "[[stack.dielectrics]] tables { name, top, k }, bottom up")
    out, below = [], 0.0
    for i, d in enumerate(raw):
        where = f"stack.dielectrics[{i}]"
        last = i == len(raw) - 1
        want = {"name", "k"} | (set() if last else {"top"})
        if set(d) != want:
            raise ConfigError(source, where, d, "{ name, top, k }" + (" (the last without top: it reaches up without "
                                                                      "end)" if last else ""))
        if not isinstance(d["name"], str) or not d["name"]:
            raise ConfigError(source, f"{where}.name", d["name"], "a name")
        kk = quantity(d["k"], "1", f"{where}.k", source)
        if not 1.0 <= kk <= 20.0:
            raise ConfigError(source, f"{where}.k", d["k"], "a relative permittivity 1 - 20")
        top = float("inf") if last else quantity(d["top"], "m", f"{where}.top", source)
        if not (top > below and top <= 1e-4 or last):
            raise ConfigError(source, f"{where}.top", d.get("top"), f"a height above the layer below ({below * 1e6:g} um), "
                              "at most 100 um")
        out.append(Dielectric(d["name"], top, kk))
        below = top
    return tuple(out)


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
