"""Device mismatch for the Monte Carlo yield: the model library's own statistics, or the
kit's Pelgrom draw per device where the library has none.

- ``library``: the model library draws every MOSFET instance itself (GF180MCU:
  ``sw_stat_mismatch = 1``, section ``fets_mm``: ``delvto`` and ``mulu0`` per instance,
  Pelgrom in sqrt(W L)), from ngspice's seed; the kit turns it on (``MISMATCH_INCLUDE``)
  and sets ``.options seed``. The seed depends on (run seed, sample) only, so every deck
  of one sample with the same circuit draws the same devices.
- ``pelgrom``: for a library without statistics, the kit draws each MOSFET's threshold
  shift, sigma = A_VT / sqrt(W L) (technology ``[mismatch] mos_avt_n`` / ``mos_avt_p``),
  from numpy seeded by (run seed, sample, device path), and writes it as a source in
  series with the gate (a threshold shift is a gate-voltage offset). Subcircuits get one
  parameter per device they hold, so every instance carries its own draw. The current
  factor is not drawn (the library path draws it: for the SF offset it adds < 1 %,
  ``physics.pelgrom``).

Both draw every AFE capacitor from the technology's capacitor matching
(``physics.pelgrom.cap_sigma_rel``), seeded by (run seed, sample, instance).

A library without statistics and a technology without ``mos_avt_*`` leave nothing to
draw: that is refused before anything runs (a Monte Carlo of identical devices would
read as a pass).
"""
from __future__ import annotations

import hashlib
import math
import zlib
from dataclasses import dataclass, replace

import numpy as np

from ..errors import ConfigError
from ..spice.netlist import Element, Param


@dataclass(frozen=True)
class Draw:
    seed: int
    sample: int
    source: str          # "library" | "pelgrom"

    @property
    def ngspice_seed(self) -> int:
        return zlib.crc32(f"verify:{self.seed}:{self.sample}".encode()) % 2_000_000_000 + 1

    def rng(self, tag: str) -> np.random.Generator:
        return np.random.default_rng([self.seed, self.sample, zlib.crc32(tag.encode())])


def library_has_statistics(design) -> bool:
    """Whether the model library carries per-instance MOSFET mismatch (GF180MCU ``fets_mm``)."""
    from ..physics.pelgrom import coefficients
    try:
        coefficients(design, "n")
        coefficients(design, "p")
    except (ConfigError, OSError):
        return False
    return True


def source(design) -> str:
    """Where the draws come from ("library" or "pelgrom"), or a ConfigError when nothing varies."""
    want = design.verify.mismatch
    lib = library_has_statistics(design)
    mm = design.tech.mismatch
    kit = mm is not None and mm.mos_avt_n is not None and mm.mos_avt_p is not None
    if want == "library" or (want == "auto" and lib):
        if not lib:
            raise ConfigError(design.source, "verify.mismatch", want,
                              "pelgrom or auto: the model library has no mismatch statistics (no fets_mm section)")
        return "library"
    if not kit:
        raise ConfigError(design.tech.source, "mismatch.mos_avt_n", None,
                          "A_VT of both MOS types ([mismatch] mos_avt_n and mos_avt_p) for the kit's Pelgrom draw: "
                          "the model library has no mismatch statistics, and a Monte Carlo of identical devices "
                          "would have zero spread")
    if mm.cap_pelgrom is None:
        raise ConfigError(design.tech.source, "mismatch.cap_pelgrom", None, "capacitor matching")
    return "pelgrom"


def describe(src: str) -> str:
    return {"library": "the model library's own mismatch statistics (per instance, sw_stat_mismatch)",
            "pelgrom": "the kit's Pelgrom draw per device (technology [mismatch] mos_avt_n / mos_avt_p)"}[src]


def apply(net, design, draw: Draw | None):
    """``net`` with the devices of sample ``draw`` (unchanged when ``draw`` is None)."""
    if draw is None:
        return net
    net = _afe_caps(net, design, draw)
    if draw.source == "library":
        from ..circuits.array import MISMATCH_INCLUDE
        return replace(net, includes=(*net.includes, MISMATCH_INCLUDE),
                       options=(*net.options, ("seed", draw.ngspice_seed)))
    return _pelgrom(net, design, draw)


def _afe_caps(net, design, draw):
    from ..physics.pelgrom import cap_sigma_rel
    a = design.afe
    out = []
    for e in net.elements:
        if e.value == "scafe":
            rng = draw.rng(f"afe:{e.name}")
            caps = [c * (1 + cap_sigma_rel(design, c) * rng.standard_normal()) for c in (a.c11, a.c12, a.c13)]
            kept = tuple((k, v) for k, v in e.params if k not in ("c11", "c12", "c13"))
            e = replace(e, params=(*kept, *zip(("c11", "c12", "c13"), caps)))
        out.append(e)
    return replace(net, elements=tuple(out))


def _pname(path: str) -> str:
    return "dvt_" + hashlib.sha1(path.encode()).hexdigest()[:12]


def _pelgrom(net, design, draw):
    """Every MOSFET with a gate source of its own drawn threshold shift (see the module)."""
    mos, mm = design.tech.mos, design.tech.mismatch
    avt = {mos.nmos: mm.mos_avt_n, mos.pmos: mm.mos_avt_p}
    subs = {s.name: s for s in net.subckts}
    devices: dict[str, list] = {}   # subckt -> [(path, model, w, l)]

    def params_of(e) -> dict:
        return {k: v for k, v in e.params}

    def devs(name: str) -> list:
        if name not in devices:
            out = []
            for e in subs[name].elements:
                if e.value in avt:
                    p = params_of(e)
                    out.append((e.name, e.value, p["w"], p["l"]))
                elif e.value in subs:
                    out += [(f"{e.name}.{path}", m, w, l) for path, m, w, l in devs(e.value)]
            devices[name] = out
        return devices[name]

    def rewrite(elements, value_of) -> list:
        out = []
        for e in elements:
            if e.value in avt:
                d, g, s, b = e.nodes
                inner = f"mmg_{e.name}"[:64]
                out += [Element(f"Vmm_{e.name}"[:64], (g, inner), value_of(e.name, e.value, params_of(e))),
                        replace(e, nodes=(d, inner, s, b))]
            elif e.value in subs:
                child = tuple((_pname(path), value_of(f"{e.name}.{path}", m, {"w": w, "l": l}))
                              for path, m, w, l in devs(e.value))
                out.append(replace(e, params=(*e.params, *child)))
            else:
                out.append(e)
        return out

    new_subs = []
    for s in net.subckts:
        own = devs(s.name)
        body = rewrite(s.elements, lambda path, _m, _p: Param(_pname(path)))
        new_subs.append(replace(s, elements=tuple(body), params=(*s.params, *((_pname(p), 0.0) for p, *_ in own))))

    def drawn(path, model, p):
        sigma = avt[model] / math.sqrt(p["w"] * p["l"])
        return float(sigma * draw.rng(f"mos:{path}").standard_normal())

    top = rewrite(net.elements, drawn)
    return replace(net, elements=tuple(top), subckts=tuple(new_subs))
