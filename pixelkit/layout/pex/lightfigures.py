"""The collection model's figures as the kit uses them: the secondary's effective opening, each
subpixel's GSE, by wavelength and over a spectrum (docs/light-collection.md).

The model (``collection.response``) gives electrons per photon incident on the cell, per junction and
wavelength. The kit's photocurrents are the technology's QE times an area (``photo.photocurrent``):
the primary's photodiode keeps that (the QE curve anchors the absolute scale, as a measured QE
would), and the model gives what the geometric light got wrong, as ratios to it:

- the **effective opening** of a secondary: the area that, lit like the primary, collects the
  secondary's signal: A_eff = A_primary x R_secondary / R_primary, R = integral of the spectrum's
  power times the junction's responsivity eta q lambda / hc (the mean of the dual pixel's
  secondaries: they differ by their neighbours' wiring);
- the **GSE** of a subpixel: R_pd / R_fd of its own photodiode and storage node (the charge ratio
  ``pixel.gse`` stands for).

``with_light(design)`` puts both on the design's subpixels (``Subpixel.modelled``), so every figure
that uses the photoactive area or the GSE (SPICE benches, sizing, frames, camera, sign-off) uses the
model. The spectrum is the scene's black body (``scene.spectrum_temperature``, CIE A = 2856 K: a
halogen headlight) or any ``photo.Spectrum``.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ...errors import ConfigError

_MEMO: dict = {}
_DRAWN: dict = {}
#: Drawn geometries kept per process (the newest).
DRAWN_KEPT = 4


def drawn(design):
    """``collection.pixel_geometry(design)`` drawn once per process and design (the same object handed
    out again: the light code only reads it; the report's light section asked for it four times, each
    a full draw, GDS write and KLayout extraction). Kept here, not in ``collection``, whose source is
    part of the light store's keys."""
    import hashlib
    from .collection import pixel_geometry
    key = hashlib.sha256(repr(design).encode()).hexdigest()
    if key not in _DRAWN:
        _DRAWN[key] = pixel_geometry(design)
        while len(_DRAWN) > DRAWN_KEPT:         # a design closure draws many variants: memory stays flat
            _DRAWN.pop(next(iter(_DRAWN)))
    return _DRAWN[key]


def nets_of(resp) -> dict:
    """{"primary": (pd, fd), "secondary": [(pd, fd), ...]} of a response's nets."""
    sec = sorted({n.split(".")[0] for n in resp.eta if n.startswith("s") and n.endswith(".pd")})
    return {"primary": ("p.pd", "p.fd"), "secondary": [(f"{s}.pd", f"{s}.fd") for s in sec]}


def responsivity(resp, net: str) -> np.ndarray:
    """A / W of light incident on the cell, per wavelength: eta q lambda / hc x 1 (per incident watt)."""
    from ...physics.photo import responsivity as r
    return r(resp.wavelength_m, resp.eta[net])


def weighted(resp, net: str, spectrum) -> float:
    """The spectrum's power-weighted mean responsivity of ``net`` (A / W); no light outside the model's
    wavelengths is counted."""
    wl, r = resp.wavelength_m, responsivity(resp, net)
    return spectrum.mean(lambda w: np.interp(w, wl, r, left=0.0, right=0.0))


def figures(design, resp, spectrum) -> dict:
    """The effective opening and the GSE over ``spectrum``, and both by wavelength."""
    nets = nets_of(resp)
    a_p = design.primary.area if design.primary.mask_opening is None else design.primary.mask_opening
    pp, pf = nets["primary"]
    rp = weighted(resp, pp, spectrum)
    sec = nets["secondary"]
    a_eff = [a_p * weighted(resp, s, spectrum) / rp for s, _ in sec]
    gse_s = [weighted(resp, s, spectrum) / weighted(resp, f, spectrum) for s, f in sec]
    eta = resp.eta
    by_wl = {"wavelength_m": resp.wavelength_m,
             "effective_opening_m2": a_p * np.mean([eta[s] for s, _ in sec], axis=0) / eta[pp],
             "gse_primary": eta[pp] / np.maximum(eta[pf], 1e-300),
             "gse_secondary": np.mean([eta[s] / np.maximum(eta[f], 1e-300) for s, f in sec], axis=0),
             "qe_primary_pd": eta[pp] * resp.cell_area_m2 / a_p,
             "opening_transmission": resp.opening_transmission}
    return {"effective_opening_m2": float(np.mean(a_eff)), "effective_openings_m2": a_eff,
            "gse_primary": rp / weighted(resp, pf, spectrum), "gse_secondary": float(np.mean(gse_s)),
            "gse_secondaries": gse_s, "primary_area_m2": a_p, "drawn_opening_m2": resp.opening_area_m2,
            "by_wavelength": by_wl}


def scene_spectrum(design):
    from ...physics.photo import Spectrum
    if design.scene is None:
        raise ConfigError(design.source, "light.model", "modelled",
                          "a [scene] table with it: the collection model weights its wavelengths by the scene's "
                          "spectrum (scene.spectrum_temperature)")
    return Spectrum.blackbody(design.scene.spectrum_temperature)


def with_light(design, say=None):
    """``design`` with the collection model's effective opening (secondary) and GSE (both subpixels)
    on its subpixels; the design as it is when ``light.model`` is ``geometric``."""
    if design.light.model != "modelled":
        return design
    from .collection import response
    spectrum = scene_spectrum(design)
    key = (repr(design.raw), design.tech.source, design.source, design.temperature)
    if key not in _MEMO:
        _MEMO[key] = figures(design, response(design, say=say), spectrum)
    f = _MEMO[key]
    return replace(design,
                   primary=replace(design.primary, modelled={"photoactive_area_m2": f["primary_area_m2"],
                                                             "gse": f["gse_primary"]}),
                   secondary=replace(design.secondary, modelled={"photoactive_area_m2": f["effective_opening_m2"],
                                                                 "gse": f["gse_secondary"]}))


def opening_table(design, n: int = 6, say=None) -> dict:
    """The secondary's effective opening against its drawn mask opening (a centred square, from the
    technology's smallest opening to the photodiode's area; ``n`` sides, log-spaced), over the scene's
    spectrum: what the sizing solves on with ``light.model = "modelled"``.

    Per wavelength the effective opening is the primary's light's part (the mask openings closed: it
    does not depend on them) plus the own light's part, which scales with the power the opening passes:
    A_own(a) = A_own(a0) (a^2 T(a)) / (a0^2 T(a0)) (a0 the drawn opening, T the modal method's
    transmission at each side: how the light spreads under the shield changes with the opening too,
    not counted; docs/light-collection.md measures the difference at one size)."""
    from ...physics import lightfield as lf
    from .collection import MODAL_MAX, optics
    spectrum = scene_spectrum(design)
    parts = _parts(design, say)
    o = optics(design, drawn(design), design.light.grid)
    op0 = o.modal[0]
    a0 = op0.a * op0.b
    wl = parts["wavelength_m"]
    t0 = transmissions(o, [(op0, w) for w in wl])
    lo = design.tech.rules.min_opening_side
    sides = np.geomspace(lo, float(np.sqrt(design.secondary.area)), n)
    ops = [lf.Opening(op0.x0 + op0.a / 2 - side / 2, op0.y0 + op0.b / 2 - side / 2, side, side) for side in sides]
    ts = transmissions(o, [(op, w) for op in ops for w in wl], MODAL_MAX).reshape(len(ops), len(wl))
    eff = []
    for side, t in zip(sides, ts):
        per_wl = parts["primary_per_wl_m2"] + parts["own_per_wl_m2"] * (side * side * t) / (a0 * t0)
        eff.append(_photon_weighted(parts["resp"], per_wl, spectrum))
    return {"side_m": sides, "drawn_m2": sides ** 2, "effective_m2": np.array(eff)}


def transmissions(o, pairs: list, modal_max: float | None = None) -> np.ndarray:
    """``lightfield.transmission(o, opening, wavelength, modal_max=...)`` of each (opening, wavelength)
    pair (``modal_max`` None: that function's default), kept in the light store beside the
    collection model's responses: the modal solves are nearly all of the sizing table's cost (tens of
    seconds of CPU, in every report) and depend only on what the key holds: each opening, each
    wavelength, the screen (its dielectric, the lattice it is solved in, its thickness), ``modal_max``
    and the physics' code. The values are the function's own, read back exactly (JSON floats)."""
    import json
    from ...physics import lightfield as lf
    from .collection import _code_hash, _digest, _store
    kw = {} if modal_max is None else {"modal_max": modal_max}
    key = _digest("transmission", _code_hash(), o.n_dielectric, o.lattice, o.shield_thickness, modal_max,
                  [(repr(op), float(w)) for op, w in pairs])
    files = _store().load(key)
    if files:
        return np.array(json.loads(files["transmission.json"].decode()), dtype=float)
    t = np.array([lf.transmission(o, op, w, **kw) for op, w in pairs], dtype=float)
    _store().save(key, {"transmission.json": json.dumps(t.tolist()).encode()})
    return t


def _photon_weighted(resp, area_per_wl, spectrum) -> float:
    """The spectrum-weighted effective area: sum of A(lambda) R_p(lambda) over sum of R_p(lambda)."""
    wl, rp = resp.wavelength_m, responsivity(resp, "p.pd")
    num = spectrum.mean(lambda w: np.interp(w, wl, rp * area_per_wl, left=0.0, right=0.0))
    return num / spectrum.mean(lambda w: np.interp(w, wl, rp, left=0.0, right=0.0))


def _parts(design, say=None) -> dict:
    """The responses with all the light, the mask openings' light alone and the primary's alone, and
    the secondary's effective opening from each by wavelength."""
    from .collection import response
    geo = drawn(design)
    r_all = response(design, geo, say=say)
    a_p = design.primary.area if design.primary.mask_opening is None else design.primary.mask_opening
    out = {"resp": r_all, "wavelength_m": r_all.wavelength_m}
    for part, key in (("small", "own_per_wl_m2"), ("large", "primary_per_wl_m2")):
        r = response(design, geo, light=part, say=say)
        sec = nets_of(r)["secondary"]
        out[key] = a_p * np.mean([r.eta[s] for s, _ in sec], axis=0) / r_all.eta["p.pd"]
    return out


def decomposition(design, say=None) -> dict:
    """Where the secondary's effective opening comes from, over the scene's spectrum: the light through
    its own mask opening (``own``: what the opening passes and the photodiode collects of it) and the
    primary's light (``primary``: the mask openings closed: carriers diffusing from under the
    primary's photodiode, light travelling under the shield); the opening's transmitted power over its
    drawn area (``transmission``, photon-weighted over the spectrum)."""
    spectrum = scene_spectrum(design)
    parts = _parts(design, say)
    r_all = parts["resp"]
    f = figures(design, r_all, spectrum)
    wl, t = r_all.wavelength_m, r_all.opening_transmission
    return {"total_m2": f["effective_opening_m2"], "drawn_m2": r_all.opening_area_m2,
            "own_m2": _photon_weighted(r_all, parts["own_per_wl_m2"], spectrum),
            "primary_m2": _photon_weighted(r_all, parts["primary_per_wl_m2"], spectrum),
            "transmission": float(spectrum.mean(lambda w: np.interp(w, wl, t) * w) / spectrum.mean(lambda w: w))}
