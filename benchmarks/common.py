"""Shared set-up of the benchmark scripts: import path, a fresh cache, the reference design."""
from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def reference_design():
    """A fresh, empty simulation cache for this run, and the reference design."""
    os.environ["PIXELKIT_CACHE"] = tempfile.mkdtemp(prefix="pk-bench-")
    from pixelkit.design import load_design
    return load_design(ROOT / "designs" / "dual_pixel_revA.toml")
