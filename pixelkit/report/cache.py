"""Cache of built report sections, so a re-run with nothing changed rebuilds nothing.

The key hashes everything a section's output depends on: the pixelkit source tree
(every ``.py`` and template), the loaded design (its full repr, technology included),
the bytes of the model files it includes, the ngspice version, the report options
and the measured-data file. An entry is the section as JSON plus its figure files,
kept in the kit's one checked store (:mod:`pixelkit.cachestore`, folder
``$PIXELKIT_CACHE/report``), as the simulation results are: a checksum over every
file it holds, verified before anything is used; a changed, truncated or swapped
entry, or anything but a regular file in its place, is said on stderr, removed and
the section rebuilt.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import sys
from functools import lru_cache
from pathlib import Path

from ..cachestore import Store
from ..fileio import write_atomic
from ..readfile import is_regular, read_bytes
from .sections import Checked, Figure, Section, Table

_PKG = Path(__file__).resolve().parents[1]


STORE = Store("report", "report-cache", "rebuilding the section")


def cache_dir() -> Path:
    return STORE.root()


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
    """Content hash of a loaded design: every field, its technology and the content of its model
    files, not where they lie: two checkouts (or two machines) of the same design, kit and models
    key a section alike and share the section cache, as the simulation cache does
    (``spice.cache``). The design file goes by its name and its bytes, however its path is spelled
    (the reproducibility section, which prints the path in its rebuild command, keys on it through its
    ``inputs``); the technology file and
    the model folders go by their names, their content being in the fields (the technology), in
    :func:`source_hash` (the kit's own files) and in the model files' fingerprint, taken over
    every corner's includes (the sign-off simulates the other corners too)."""
    from ..tech.modellib import content_fingerprint
    lib = design.tech.models
    incs = [*(i for corner in lib.corners.values() for i in corner), *lib.mim.values()]
    text = repr(design)
    src = getattr(design, "source", None)
    if src:        # the file by its name (its bytes are hashed below), however its path is spelled
        text = text.replace(f"source={src!r}", f"source={Path(src).name!r}")
    tech_source = getattr(design.tech, "source", None)
    names = {str(lib.folder): "<models>", **{str(i.folder): "<models>" for i in incs}}
    if tech_source:
        names[str(tech_source)] = Path(tech_source).name
    for path in sorted(names, key=len, reverse=True):   # a folder inside another is replaced first
        text = text.replace(path, names[path])
    h = hashlib.sha256(text.encode())
    h.update(content_fingerprint(tuple(sorted({str(i.file) for i in incs}))).encode() if incs else b"")
    if src and is_regular(Path(src)):
        h.update(read_bytes(Path(src), "design", "design"))
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
    """The cached section ``k`` with its files written into ``out_dir``, or None."""
    files = STORE.load(k)
    if files is None:
        return None
    try:
        raw = json.loads(files.pop("section.json"))
        s = _from_dict(raw)
        if sorted(raw["files"]) != sorted(files):
            raise ValueError("the files listed are not the files held")
        if any(Path(n).is_absolute() or ".." in Path(n).parts for n in files):
            raise ValueError("a file name outside the report folder")
    except (KeyError, ValueError, TypeError) as exc:   # checksummed, yet not a section: another version
        sys.stderr.write(f"pixelkit: warning: cache entry {STORE.path(k)} holds no section ({exc}); "
                         "rebuilding the section\n")
        STORE.drop(k)
        return None
    for name, blob in files.items():
        write_atomic(out_dir / name, blob)
    return s


def save(k: str, section: Section, out_dir: Path) -> None:
    names = [f.file for f in section.figures if is_regular(out_dir / f.file)]
    names += [n for n in section.files if is_regular(out_dir / n)]
    files = {n: read_bytes(out_dir / n, "section file", "report-cache") for n in dict.fromkeys(names)}
    files["section.json"] = json.dumps(dict(dataclasses.asdict(section), files=list(files))).encode()
    STORE.save(k, files)


def _from_dict(raw: dict) -> Section:
    raw = {k: v for k, v in raw.items() if k != "files"}
    raw["tables"] = [Table(**t) for t in raw["tables"]]
    raw["figures"] = [Figure(**f) for f in raw["figures"]]
    raw["checked"] = [Checked(**c) for c in raw["checked"]]
    return Section(**raw)
