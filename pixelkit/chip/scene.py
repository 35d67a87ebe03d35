"""Scenes: a photocurrent per subpixel from a scene map (CSV, NumPy, image) or a default scene.

A scene is a 2-D map over the sensor, resampled (area average) to the secondary grid
(rows x N cols); each primary subpixel sees the mean of the N secondary positions it
covers. Units of the map (``unit``):

- ``lx``   scene illuminance of a Lambertian scene of the design's reflectance, imaged by
  the design's optics: E_sensor = rho T E_scene / (4 N^2) (``optimize.sizing.light``),
  turned into a photocurrent density with the design's spectrum and the technology's QE;
- ``W/m2`` irradiance at the sensor plane (same spectrum and QE);
- ``A/m2`` photocurrent density at the sensor;
- ``rel``  (images, default for them) 0..1 scaled to 0 .. 2 x the design's background
  illuminance (``scene.background``, which sizing puts at the primary's mid-scale);
- ``fs``   fraction of the primary's full scale over its ``t_int`` (1 = the PD drops by the
  design's ``pixel.swing``); the default scenes use it, so they are sane whatever the light.

Photocurrent = density x the subpixel's photoactive area (the secondary's mask opening).

Exposure: a frame is simulated over ``t_exp`` (default the experiment window, 16 us,
so the whole array stays affordable) while the design integrates over ``t_int``
(1 ms primary, 12 ms secondary). The kit keeps the charge of the real frame: it
simulates ``I t_int / t_exp`` (charge-equivalent compression; dark current is not
scaled, so the dark signal is that of ``t_exp``). A subpixel whose current would take its PD
below ``V_FLOOR`` within the exposure is saturated: it is counted in ``clipped`` (and marked in
``saturated``) and simulated at its full current, its PD forward-biasing as silicon does
(``docs/timing-and-settling.md``); the stimulus is never capped.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ConfigError
from ..fileio import path_kind

UNITS = ("lx", "W/m2", "A/m2", "rel", "fs")
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")
KINDS_OF_DEFAULT = ("gradient", "uniform")
V_FLOOR = 0.2  # V: a subpixel whose PD would go below this in the exposure is counted as clipped (saturated)


@dataclass
class Photocurrents:
    iph_p: np.ndarray       # rows x cols (A, as simulated)
    iph_s: np.ndarray       # rows x N cols (A, as simulated)
    compression: dict       # kind -> t_int / t_exp
    clipped: dict           # kind -> number of saturated subpixels (beyond full well)
    saturated: dict = None  # kind -> rows x cols bool array: those subpixels

    def as_dict(self) -> dict:
        return {"iph_primary_A": self.iph_p.tolist(), "iph_secondary_A": self.iph_s.tolist(),
                "compression": self.compression, "clipped": self.clipped}


def load_map(path) -> tuple[np.ndarray, str]:
    """A 2-D map from ``.csv`` (numbers; one header line allowed), ``.npy`` or an image;
    returns (map, default unit)."""
    from PIL import Image

    from ..readfile import open_file, read_text
    p = Path(path)
    if path_kind(p) is None:
        raise ConfigError(str(p), "scene", str(p), "an existing .csv, .npy or image file")
    suffix = p.suffix.lower()
    try:
        if suffix == ".npy":
            with open_file(p, "scene", "scene") as fh:
                m, unit = _read_npy(p, fh), "lx"
        elif suffix == ".csv":
            m = _read_csv(p, read_text(p, "scene", "scene"))
            unit = "lx"
        elif suffix in IMAGE_SUFFIXES:
            import matplotlib.image as mpimg
            with open_file(p, "scene", "scene") as fh:
                img = np.asarray(mpimg.imread(fh, format=suffix[1:]), float)
            if img.ndim == 3:  # RGB(A): Rec. 709 luma of the colour channels
                img = img[..., :3] @ np.array([0.2126, 0.7152, 0.0722])
            m, unit = img / (img.max() if img.max() > 1 else 1.0), "rel"
        else:
            raise ConfigError(str(p), "scene", suffix, f"one of .csv, .npy, {', '.join(IMAGE_SUFFIXES)}")
    except (OSError, ValueError, Image.DecompressionBombError) as exc:
        raise ConfigError(str(p), "scene", p.name, f"a readable scene file ({exc})") from None
    m = np.asarray(m, float)
    if m.ndim != 2 or min(m.shape) < 1:
        raise ConfigError(str(p), "scene", f"shape {m.shape}", "a 2-D map")
    if not np.all(np.isfinite(m)) or m.min() < 0:
        raise ConfigError(str(p), "scene", "negative or non-finite values", "finite values >= 0")
    return m, unit


#: the most pixels a scene map may declare (a 16k x 16k sensor); what a map declares must also be in
#: the file, whose size readfile bounds: no allocation is ever larger than the file itself
MAX_SCENE_PIXELS = 16384 * 16384


def _read_npy(p: Path, fh) -> np.ndarray:
    """A ``.npy`` map, its header checked before anything is allocated (readfile.npy_array)."""
    import os

    from ..readfile import npy_array
    m = npy_array(fh, os.fstat(fh.fileno()).st_size, p, "scene", max_items=MAX_SCENE_PIXELS)
    if m.ndim != 2:
        raise ConfigError(str(p), "scene", f"shape {m.shape}", "a 2-D map")
    return m


def _read_csv(p: Path, text: str) -> np.ndarray:
    lines = [ln for ln in text.splitlines() if ln.strip()]
    try:
        float(lines[0].split(",")[0])
    except (ValueError, IndexError):
        lines = lines[1:]  # a header line
    try:
        return np.array([[float(x) for x in ln.split(",")] for ln in lines])
    except ValueError as exc:
        raise ConfigError(str(p), "scene", str(exc), "comma-separated numbers") from None


def default_map(rows: int, cols: int, kind: str = "gradient") -> tuple[np.ndarray, str]:
    """``gradient``: 5 % .. 80 % of the primary's full scale, left to right; ``uniform``: 50 %."""
    if kind not in KINDS_OF_DEFAULT:
        raise ConfigError("", "scene", kind, f"a file, or one of {', '.join(KINDS_OF_DEFAULT)}")
    if kind == "uniform":
        return np.full((rows, cols), 0.5), "fs"
    return np.tile(np.linspace(0.05, 0.8, cols), (rows, 1)), "fs"


def resample(m: np.ndarray, rows: int, cols: int) -> np.ndarray:
    """Area-average resampling of ``m`` to rows x cols (exact for integer ratios)."""
    def axis_weights(n_in, n_out):
        edges_in = np.linspace(0, 1, n_in + 1)
        edges_out = np.linspace(0, 1, n_out + 1)
        w = np.zeros((n_out, n_in))
        for i in range(n_out):
            lo, hi = edges_out[i], edges_out[i + 1]
            w[i] = np.clip(np.minimum(edges_in[1:], hi) - np.maximum(edges_in[:-1], lo), 0, None)
        return w / w.sum(axis=1, keepdims=True)
    return axis_weights(m.shape[0], rows) @ m @ axis_weights(m.shape[1], cols).T


def density(design, m: np.ndarray, unit: str) -> np.ndarray:
    """Photocurrent density (A/m^2) at the sensor for map ``m`` in ``unit``."""
    if unit not in UNITS:
        raise ConfigError("", "scene unit", unit, f"one of {', '.join(UNITS)}")
    if unit == "A/m2":
        return m
    if unit == "fs":
        p = design.primary
        return m * i_floor(design, "primary", p.t_int, design.pixel.v_pd_reset - design.pixel.swing) \
            / p.photoactive_area
    from ..optimize.sizing import light
    from ..physics.photo import Spectrum, responsivity
    if design.optics is None or design.scene is None:
        raise ConfigError(design.source, "optics", None, f"[optics] and [scene] tables for a scene in {unit}")
    lt = light(design)                     # j_bg: density of the background illuminance
    if unit == "lx":
        return m * lt.j_bg / design.scene.background
    if unit == "rel":
        return m * 2 * lt.j_bg
    spec = Spectrum.blackbody(design.scene.spectrum_temperature)
    return m * spec.mean(lambda wl: responsivity(wl, design.tech.qe(wl)))


def i_floor(design, kind: str, t_exp: float, v_end: float = V_FLOOR) -> float:
    """The photocurrent that takes the PD node from its reset level to ``v_end`` in ``t_exp``."""
    from ..physics.subpixel import pd_node
    node = pd_node(design, kind, parasitics=True)
    return float(node.charge(design.pixel.v_pd_reset) - node.charge(v_end)) / t_exp


def photocurrents(design, rows: int, cols: int, m: np.ndarray, unit: str,
                  t_exp: float | None = None, compress: bool = True) -> Photocurrents:
    """Simulated photocurrents of a rows x cols array (both arrays) under map ``m``."""
    n = design.secondary_per_pixel
    t_exp = design.experiment.t_window if t_exp is None else t_exp
    j = density(design, resample(np.asarray(m, float), rows, n * cols), unit)
    out, comp, clipped, sat = {}, {}, {}, {}
    for kind in ("primary", "secondary"):
        sub = getattr(design, kind)
        jj = j if kind == "secondary" else j.reshape(rows, cols, n).mean(axis=2)
        comp[kind] = sub.t_int / t_exp if compress else 1.0
        i = jj * sub.photoactive_area * comp[kind]
        hi = i_floor(design, kind, t_exp)
        sat[kind] = i > hi
        clipped[kind] = int(np.count_nonzero(sat[kind]))
        out[kind] = i
    return Photocurrents(out["primary"], out["secondary"], comp, clipped, sat)


def default_stimulus(design, t_exp: float) -> dict:
    """Half of the primary's swing and 5 % of the secondary's over ``t_exp`` (PD model)."""
    v_end = design.pixel.v_pd_reset - design.pixel.swing
    return {"iph_p": 0.5 * i_floor(design, "primary", t_exp, v_end),
            "iph_s": 0.05 * i_floor(design, "secondary", t_exp, v_end), "t_exp": t_exp}
