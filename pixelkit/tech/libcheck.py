"""What a model library defines for each corner, so a technology is checked when it loads.

Each device name a technology uses (``mos.nmos``, ``mos.pmos`` as ``.subckt`` or ``.model``
cards by ``mos.kind``; ``photodiode.spice_model`` as a ``.model`` card when the kit does not
write it) must be defined by what every corner it lists includes, and every listed corner
must resolve (each ``lib FILE SECTION`` names a section that exists, each nested reference
too). Otherwise the technology is refused with exit 2 naming the key, instead of failing
later inside ngspice with no field named.

The library is read as ngspice reads it (ngspice 39): a ``lib FILE SECTION`` line takes the
lines of ``.lib SECTION`` ... ``.endl`` in FILE, where a nested ``.lib 'file' section``
takes that section in turn (paths relative to the file that holds the line) and an
``.include`` takes the file's lines outside its sections; names compare without case.
Files are read through :mod:`pixelkit.readfile` (bounded) and parsed once per version.
"""
from __future__ import annotations

import re
from functools import lru_cache
from pathlib import Path

from ..errors import ConfigError
from ..readfile import FileRefused, read_bytes
from .modellib import file_stamp

_SECTION_START = re.compile(r"^[ \t]*\.lib[ \t]+([^\s'\"]+)[ \t]*(\*.*)?$", re.I)
_SECTION_REF = re.compile(r"""^[ \t]*\.lib[ \t]+(?:'([^']+)'|"([^"]+)"|([^\s'"]+))[ \t]+([^\s*]+)""", re.I)
_ENDL = re.compile(r"^[ \t]*\.endl\b", re.I)
_INCLUDE = re.compile(r"""^[ \t]*\.inc(?:lude)?[ \t]+['"]?([^'"\s]+)""", re.I)
_DEFINES = re.compile(r"^[ \t]*\.(subckt|model)[ \t]+([^\s(]+)", re.I)
_DEPTH = 30


class Unresolved(Exception):
    """A corner's include does not resolve: the message says which file or section."""


@lru_cache(maxsize=16)
def _parse(path: str, _size: int, _mtime_ns: int) -> tuple[tuple, dict]:
    """(lines outside any section, {section name (lower case): its lines})."""
    try:
        text = read_bytes(path, "model file", "model").decode("latin-1")
    except FileRefused as exc:
        raise Unresolved(f"{Path(path).name}: {exc.value}") from None
    top, sections, name, body = [], {}, None, []
    for line in text.split("\n"):
        if name is None:
            start = _SECTION_START.match(line)
            if start and not _SECTION_REF.match(line.split("*")[0]):
                name, body = start.group(1).lower(), []
            else:
                top.append(line)
        elif _ENDL.match(line):
            sections.setdefault(name, tuple(body))
            name = None
        else:
            body.append(line)
    return tuple(top), sections


def _lines(path: Path, section: str | None) -> tuple:
    stamp = file_stamp(str(path))
    if stamp[1] < 0:
        raise Unresolved(f"file {path.name} not found")
    top, sections = _parse(*stamp)
    if section is None:
        return top
    if section.lower() not in sections:
        raise Unresolved(f"section {section} not found in {path.name}")
    return sections[section.lower()]


def _defined(path: Path, section: str | None, depth: int, out: dict) -> None:
    if depth > _DEPTH:
        raise Unresolved(f"references nested deeper than {_DEPTH} (a cycle?) at {path.name}")
    for line in _lines(path, section):
        if not line.lstrip().startswith("."):
            continue
        d = _DEFINES.match(line)
        if d:
            out.setdefault(d.group(2).lower(), d.group(1).lower())
            continue
        ref = _SECTION_REF.match(line)
        if ref:
            name = next(g for g in ref.groups()[:3] if g)
            _defined((path.parent / name).resolve(), ref.group(4), depth + 1, out)
            continue
        inc = _INCLUDE.match(line)
        if inc:
            _defined((path.parent / inc.group(1)).resolve(), None, depth + 1, out)


@lru_cache(maxsize=64)
def _corner_defines(includes: tuple, _stamps: tuple) -> dict:
    out: dict = {}
    for inc in includes:
        _defined(inc.file.resolve(), inc.section if inc.kind == "lib" else None, 0, out)
    return out


def corner_defines(includes) -> dict:
    """{device name (lower case): 'subckt' | 'model'} of everything a corner's includes define;
    Unresolved when an include does not resolve."""
    includes = tuple(includes)
    return _corner_defines(includes, tuple(file_stamp(str(i.file)) for i in includes))


def check_devices(tech, source: str) -> None:
    """Refuse (exit 2, naming the key) a device name missing from any corner, or a corner that
    does not resolve."""
    kind = "subckt" if tech.mos.kind == "subckt" else "model"
    wanted = [("mos.nmos", tech.mos.nmos, kind), ("mos.pmos", tech.mos.pmos, kind)]
    if not tech.photodiode.builtin_model:
        wanted.append(("photodiode.spice_model", tech.photodiode.spice_model, "model"))
    for corner, includes in tech.models.corners.items():
        try:
            found = corner_defines(includes)
        except Unresolved as exc:
            raise ConfigError(source, f"models.corners.{corner}", [f"{i.kind} {i.name} {i.section}".strip() for i in includes],
                              f"includes that resolve in the model folder ({exc})") from None
        bins = {n.rsplit(".", 1)[0] for n, c in found.items() if c == "model" and n.rsplit(".", 1)[-1].isdigit()}
        for key, name, card in wanted:
            if found.get(name.lower()) != card and not (card == "model" and name.lower() in bins):
                have = sorted(n for n, c in found.items() if c == card)
                other = f" (it is a .{found[name.lower()]} there, mos.kind says .{card})" if name.lower() in found else ""
                raise ConfigError(source, key, name, f"a .{card} the model library defines for corner "
                                  f"'{corner}'{other}; that corner defines {len(have)}: "
                                  f"{', '.join(have[:12])}{' ...' if len(have) > 12 else ''}")
