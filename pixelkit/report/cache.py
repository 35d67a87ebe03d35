"""Cache of built report sections, so a re-run with nothing changed rebuilds nothing.

The key hashes everything a section's output depends on: the pixelkit source tree
(every ``.py`` and template), the loaded design (its full repr, technology included),
the bytes of the model files it includes, the ngspice version, the report options
and the measured-data file. An entry is the section as JSON plus its figure files,
under ``$PIXELKIT_CACHE/report/<key>/`` (written through a temporary folder, then
renamed, so a half-written entry is never read).
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import shutil
import tempfile
from functools import lru_cache
from pathlib import Path

from .sections import Checked, Figure, Section, Table

_PKG = Path(__file__).resolve().parents[1]


def cache_dir() -> Path:
    return Path(os.environ.get("PIXELKIT_CACHE", Path.home() / ".cache" / "pixelkit")) / "report"


@lru_cache(maxsize=1)
def source_hash() -> str:
    """Hash of the pixelkit package's code and templates (any edit invalidates every section)."""
    h = hashlib.sha256()
    for p in sorted(_PKG.rglob("*")):
        if p.suffix in (".py", ".j2", ".css", ".toml") and "__pycache__" not in p.parts:
            h.update(str(p.relative_to(_PKG)).encode())
            h.update(p.read_bytes())
    return h.hexdigest()[:16]


def design_hash(design) -> str:
    """Content hash of a loaded design: every field, its technology and its model files."""
    from ..tech.modellib import files_fingerprint
    files = tuple(sorted(str(i.file) for i in design.tech.models.includes(design.corner or None)))
    text = repr(design)
    if getattr(design, "source", None):   # the same file however its path is spelled
        text = text.replace(f"source={design.source!r})", f"source={str(Path(design.source).resolve())!r})")
    h = hashlib.sha256(text.encode())
    h.update(files_fingerprint(files).encode() if files else b"")
    return h.hexdigest()[:16]


def file_hash(path) -> str:
    from ..readfile import sha256_file
    return sha256_file(path, "--measured", "csv")[:16]


def section_key(key: str, design, options: dict) -> str:
    from ..spice.batch import ngspice_version
    h = hashlib.sha256()
    for part in (key, source_hash(), design_hash(design), ngspice_version(), json.dumps(options, sort_keys=True)):
        h.update(str(part).encode())
        h.update(b"\0")
    return h.hexdigest()[:24]


def load(k: str, out_dir: Path) -> Section | None:
    """The cached section ``k`` with its files copied into ``out_dir``, or None."""
    entry = cache_dir() / k
    try:
        raw = json.loads((entry / "section.json").read_text())
        s = _from_dict(raw)
        for name in raw["files"]:
            (out_dir / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(entry / name, out_dir / name)
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return s


def save(k: str, section: Section, out_dir: Path) -> None:
    files = [f.file for f in section.figures if (out_dir / f.file).exists()]
    files += [n for n in section.files if (out_dir / n).exists()]
    root = cache_dir()
    root.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{k}.", dir=root))
    try:
        for name in files:
            (tmp / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(out_dir / name, tmp / name)
        (tmp / "section.json").write_text(json.dumps(dict(dataclasses.asdict(section), files=files)))
        if (root / k).exists():
            shutil.rmtree(root / k, ignore_errors=True)
        os.replace(tmp, root / k)
    except OSError:
        shutil.rmtree(tmp, ignore_errors=True)  # a cache that cannot be written is only slower


def _from_dict(raw: dict) -> Section:
    raw = {k: v for k, v in raw.items() if k != "files"}
    raw["tables"] = [Table(**t) for t in raw["tables"]]
    raw["figures"] = [Figure(**f) for f in raw["figures"]]
    raw["checked"] = [Checked(**c) for c in raw["checked"]]
    return Section(**raw)
