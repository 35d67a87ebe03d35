"""Everything needed to reproduce each figure: simulator, options, corner, temperature,
versions and content hashes (design, technology + model files, code, each netlist)."""
from __future__ import annotations

import hashlib
import platform
import subprocess
from importlib import metadata
from pathlib import Path

from . import Section, Table

TITLE = "Reproducibility"
PACKAGES = ("pixelkit", "numpy", "scipy", "casadi", "matplotlib", "PySpice", "pyvista", "gdstk", "klayout",
            "jinja2", "schemdraw", "click")


def _version(name: str) -> str:
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return "not installed"


def _git() -> str:
    root = Path(__file__).resolve().parents[3]
    try:
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return head or "not a git checkout"


def inputs(ctx) -> dict:
    """What the section shows besides the design and the kit's code (the report's section cache keys
    on it): the checkout's git commit, which a commit that changes no code still moves, and the design's
    path as spelled, which its rebuild command prints (the design's key has its file's name only)."""
    return {"git": _git(), "source": str(getattr(ctx.design, "source", None))}


def build(ctx) -> Section:
    from ...registry import GENERATORS, golden_text
    from ...spice.batch import ngspice_version
    from ...spice.options import DEFAULTS, RETRIES
    from ...tech.modellib import content_fingerprint
    from ..cache import design_hash, source_hash
    d = ctx.design
    corner = d.corner or d.tech.models.default_corner
    incs = d.tech.models.includes(d.corner or None)
    files = tuple(sorted(str(i.file) for i in incs))
    sim = [["simulator", f"ngspice {ngspice_version()}"], ["backend", ctx.backend],
           ["options", " ".join(f"{k}={v}" for k, v in DEFAULTS)],
           ["retry options (on failure only)", " ".join(f"{k}={v}" for k, v in RETRIES[0])],
           ["model corner", corner], ["temperature (degC)", round(d.temperature - 273.15, 2)],
           ["technology", d.tech.name], ["model files", ", ".join(Path(f).name for f in files)],
           ["profile", "quick" if ctx.quick else "full"], ["python", platform.python_version()],
           ["platform", platform.platform()], ["pixelkit source (git)", _git()]]
    versions = [[p, _version(p)] for p in PACKAGES]
    src = Path(d.source) if d.source else None
    hashes = [["design file " + (src.name if src else "(in memory)"),
               hashlib.sha256(src.read_bytes()).hexdigest()[:16] if src and src.is_file() else "-"],
              ["loaded design + technology + model files", design_hash(d)],
              ["model files (names and bytes)", content_fingerprint(files)[:16] if files else "-"],
              ["pixelkit code and templates", source_hash()]]
    hashes += [[f"netlist {n}", hashlib.sha256(golden_text(n, d).encode()).hexdigest()[:16]] for n in GENERATORS]
    cmd = f"pixelkit report {d.source or 'DESIGN'} --out <folder>" + (" --quick" if ctx.quick else "")
    return Section(TITLE, text=[f"Rebuild this report with: {cmd}. Each section is cached under the hashes "
                                "below; each SPICE run is cached under its deck text, model-file bytes, ngspice "
                                "version and backend, so equal hashes give the same figures."],
                   tables=[Table("repro_simulation", "Simulator and conditions", ["item", "value"], sim),
                           Table("repro_versions", "Software versions", ["package", "version"], versions),
                           Table("repro_hashes", "Content hashes (sha256, first 16 hex digits)", ["content", "hash"],
                                 hashes)])
