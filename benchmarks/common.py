"""Shared set-up of the benchmark scripts: import path, a fresh cache, the reference design and the
thesis read of [Thesis2019] (the chip the gap module's virtual silicon is of)."""
from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


THESIS_READ = ROOT / "designs" / "dual_pixel_revA_thesis_read.toml"


def reference_design(path: Path = ROOT / "designs" / "dual_pixel_revA.toml"):
    """A fresh, empty simulation cache for this run, and the design at ``path`` (the reference design)."""
    os.environ["PIXELKIT_CACHE"] = tempfile.mkdtemp(prefix="pk-bench-")
    from pixelkit.design import load_design
    return load_design(path)


def child_cpu_s() -> float:
    """CPU seconds (user + system) of every child process waited for so far (ngspice, KLayout)."""
    import resource
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def empty_gds(path: Path, design) -> Path:
    """A GDS of one cell EMPTY holding a 1 um boundary box: the DRC deck's fixed cost on nothing."""
    import gdstk
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    cell = gdstk.Cell("EMPTY")
    b = design.tech.layer("boundary")
    cell.add(gdstk.rectangle((0, 0), (1, 1), layer=b.layer, datatype=b.datatype))
    lib.add(cell)
    lib.write_gds(str(path))
    return path


def chip_slice(argv, cols: int, scene: str, extra=()):
    """The arguments of a chip-slice benchmark (``DESIGN --rows R --cols C [--scene S] --json`` and
    ``extra``: (flag, default) pairs), the design and the photocurrents ``pixelkit array`` gives it."""
    import argparse
    ap = argparse.ArgumentParser()
    ap.add_argument("design", nargs="?", default=str(ROOT / "designs" / "dual_pixel_revA.toml"))
    ap.add_argument("--rows", type=int, default=9)
    ap.add_argument("--cols", type=int, default=cols)
    ap.add_argument("--scene", default=scene)
    ap.add_argument("--json", action="store_true")
    for flag, default in extra:
        ap.add_argument(flag, default=default)
    a = ap.parse_args(argv)
    from pixelkit.api import load_design
    from pixelkit.chip.scene import default_map, photocurrents
    d = load_design(a.design)
    m, unit = default_map(a.rows, d.secondary_per_pixel * a.cols, a.scene)
    return a, d, photocurrents(d, a.rows, a.cols, m, unit)


def frame_runs(design, ph, variants: dict, prefix: str) -> tuple[dict, dict]:
    """The chip slice ``ph`` simulated as ``pixelkit array --afe`` does (column chains, settling reads)
    once per ``variants`` entry (name -> keyword arguments of ``simulate_frame``), in order, each on a
    fresh empty simulation cache: ({name: CPU of ngspice, wall, decks, load}, {name: Frame})."""
    import os
    import tempfile
    import time

    from pixelkit.chip.frame import simulate_frame
    runs, frames = {}, {}
    for name, kw in variants.items():
        os.environ["PIXELKIT_CACHE"] = tempfile.mkdtemp(prefix=prefix)
        load0 = os.getloadavg()[0]
        c0, t0 = child_cpu_s(), time.perf_counter()
        f = simulate_frame(design, ph.iph_p, ph.iph_s, with_afe=True, settling=True, compression=ph.compression, **kw)
        runs[name] = {"cpu_s": round(child_cpu_s() - c0, 2), "wall_s": round(time.perf_counter() - t0, 1),
                      "decks": f.decks, "failures": len(f.failures),
                      "load": [round(load0, 1), round(os.getloadavg()[0], 1)]}
        frames[name] = f
    return runs, frames
