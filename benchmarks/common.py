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
