"""Write the virtual camera's exposure series as an EMVA 1288 descriptor dataset.

The layout of the EMVA 1288 datasets (``tests/data/emva1288/``) and of the emva1288 reference
implementation: ``EMVA1288_Data.txt`` (``v 3.0``; ``n bits width height``; ``b
exposure photons`` / ``d exposure`` each followed by ``i images/<file>.png``: two
images per temporal step, a stack of ``stack`` images for the spatial steps) and
an ``images/`` folder of grayscale PNGs (16 bit for an ADC of more than 8). The
exposure column is in nanoseconds (the reference implementation's unit; its dark
current figure multiplies by 1e9), photons are per pixel.

The folder is built beside the target and renamed into place: an interrupted
export leaves no half-written dataset.
"""
from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import numpy as np

from ..errors import PixelkitError
from ..fileio import check_output, honour_umask_tree, out_folder, path_kind
from .png16 import png_bytes
from .ptc import frame


def _spatial_step(cam, s) -> int:
    """The step nearest half the clip level (EMVA: spatial stacks at ~50 %)."""
    n = cam.eta * s.mu_p + cam.dark_e_per_s * s.t_exp_s
    return int(np.argmin(np.abs(cam.signal_V(n) - 0.5 * cam.clip_V)))


def check_target(folder) -> Path:
    """A dataset folder may be new or a previous dataset (replaced); anything else is refused."""
    folder = check_output(folder)
    if path_kind(folder) is not None and path_kind(folder / "EMVA1288_Data.txt") != "file":
        raise PixelkitError(f"{folder}: exists and is not an EMVA 1288 dataset; choose a new folder")
    return folder


def write_dataset(folder, cam, s, mm, seed: int, stack: int = 16) -> Path:
    """Write the dataset of ``cam`` (series ``s``, mismatch ``mm``) to ``folder``; returns it."""
    folder = check_target(folder)
    bits = 8 if cam.adc.bits <= 8 else 16
    rng = np.random.default_rng([seed, 11 if cam.name == "primary" else 12])
    out_folder(folder.parent)   # checked or made (fileio)
    tmp = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", dir=folder.parent))
    try:
        (tmp / "images").mkdir()
        lines = [f"# EMVA 1288 dataset of the virtual camera: {cam.name} array, seed {seed}",
                 f"# ADC {cam.adc.bits} bit stored as {bits}-bit PNG; exposure in ns, photons per pixel",
                 "v 3.0", f"n {cam.adc.bits} {cam.cols} {cam.rows}"]

        def images(tag, photons, t, count):
            out = []
            for j in range(count):
                name = f"images/{tag}_snap_{j:03d}.png"
                (tmp / name).write_bytes(png_bytes(frame(cam, mm, photons, t, rng), bits))
                out.append(f"i {name}")
            return out

        for k, (t, p) in enumerate(zip(s.t_exp_s, s.mu_p)):
            lines += [f"b {t * 1e9:.3f} {p:.4f}", *images(f"b_{k:03d}", p, t, 2)]
        ks = _spatial_step(cam, s)
        lines += [f"b {s.t_exp_s[ks] * 1e9:.3f} {s.mu_p[ks]:.4f}", *images("b_s_000", s.mu_p[ks], s.t_exp_s[ks], stack)]
        for k, t in enumerate(s.t_exp_s):
            lines += [f"d {t * 1e9:.3f}", *images(f"d_{k:03d}", 0.0, t, 2)]
        lines += [f"d {s.t_exp_s[ks] * 1e9:.3f}", *images("d_s_000", 0.0, s.t_exp_s[ks], stack)]
        (tmp / "EMVA1288_Data.txt").write_text("\n".join(lines) + "\n")
        honour_umask_tree(tmp)
        old = None
        if path_kind(folder) is not None:
            old = folder.with_name(f".{folder.name}.old")
            shutil.rmtree(old, ignore_errors=True)
            folder.rename(old)
        tmp.rename(folder)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return folder
