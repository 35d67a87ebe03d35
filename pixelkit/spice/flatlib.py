"""Model-library sections flattened once per process, so ngspice does not pre-process the whole library per deck.

A deck names its corner as ``.lib "models/sm141064.ngspice" typical``. ngspice
then reads and pre-processes the whole 1.3 MB, 47,000-line GF180 file (it opens it
once), not only the ~8,000 lines the corner's nested references select: 0.04 -
0.08 s of each deck's start-up, measured here on ngspice 39 (``benchmarks/run.py``
``flattened_vs_lib``: the dual-pixel bench runs in 0.80 - 0.85 of its ``.lib`` time),
some 10 % of a whole-chip frame's CPU time.

The runner therefore hands ngspice the section already expanded: this module
reads the library once, expands the references itself and writes the result
as one plain file in the run's scratch root (``flatlib/<hash>.lib``), and the
deck's ``.lib`` line becomes an ``.include`` of it. The deck the user sees, the
cache key and the golden netlists keep the ``.lib`` line: only what ngspice reads
changes, and it must change nothing else.

The expansion follows ngspice's semantics, measured on ngspice 39 rather than
assumed: a reference is replaced by the named section's lines in place, each
time it appears (a section referenced twice is expanded twice: a device line in
it is then reported as a duplicate), recursively; the file of a reference is
resolved from the real folder of the file that holds it (a linked file's
target); section names compare without (ASCII) case; a section ends at its
``.endl`` (whose name is not checked: GF180's ``.LIB dio`` ends with ``.endl
diode``); files are split at newlines only. The module flattens only what it
reads exactly as ngspice does and leaves the deck's own ``.lib`` line to ngspice
for anything else: an ``.include``, ``.control``, ``@`` line, ``\\`` line end or
stray carriage return anywhere in a file it reads, a continuation of a ``.lib``
or ``.endl`` line, a ``.lib`` / ``.endl`` line of any other shape (ngspice matches
them as prefixes: ``.library``, ``.endlx``; comments after them; quoted names with
spaces), a reference leaving the model folder, two files whose names differ only
in case (ngspice takes them as one), a non-ASCII section name, a missing file or
section, a cycle, a section defined twice.

Independent check (``tests/test_flatlib.py``, ngspice's own ``.lib`` processing):
decks of every corner, the GF180 diode sections, the Monte Carlo mismatch include
and the AFE give bit-identical vectors both ways; 13 quirk cases from an
independent review each give ngspice's numbers, flattened or left to ngspice as
listed; no control block reaches ngspice through a linked file.
"""
from __future__ import annotations

import hashlib
import re
import threading
from functools import lru_cache
from pathlib import Path

from ..fileio import path_kind, write_atomic
from ..readfile import FileRefused, read_bytes
from ..tech.modellib import Include, file_stamp

LINK = "flatlib"
_TOKEN = r"[^'\"\s]+"  # ngspice ends a file or section token at white space or a quote
_DEFINE = re.compile(rf"^[ \t]*\.lib[ \t]+({_TOKEN})[ \t]*$", re.I)
_REFERENCE = re.compile(rf"""^[ \t]*\.lib[ \t]+(?:'({_TOKEN})'|"({_TOKEN})"|({_TOKEN}))[ \t]+({_TOKEN})[ \t]*$""", re.I)
_ENDL = re.compile(r"^[ \t]*\.endl([ \t].*)?$", re.I)
_LIB_OR_ENDL = re.compile(r"^[ \t]*\.(lib|endl)", re.I)  # ngspice matches these as prefixes
_REFUSED = re.compile(r"^[ \t]*(\.inc|\.control|\.endc|@)", re.I)
_CONTINUATION = re.compile(r"^[ \t]*\+")
_COMMENT_OR_BLANK = re.compile(r"^[ \t]*([*$]|$)")
_DEPTH = 50
_LOCK = threading.Lock()


class _NotFlat(Exception):
    """The section holds something this module does not reproduce exactly."""


def run_deck(text: str, links: dict, includes, root: Path) -> tuple[str, dict]:
    """(deck text, links) as ngspice should read them: each flattenable ``.lib`` line
    replaced by an ``.include`` of its flattened section in ``root/flatlib``."""
    link_of = {folder: name for name, folder in links.items()}
    out_links = dict(links)
    for inc in includes:
        if inc.kind != "lib":
            continue
        name = _flat_file(inc, root)
        if name is None:
            continue
        line = inc.line(link_of[inc.folder]) + "\n"
        if line in text:
            text = text.replace(line, f'.include "{LINK}/{name}"\n', 1)
            out_links[LINK] = root / LINK
    return text, out_links


def _flat_file(inc: Include, root: Path) -> str | None:
    """The flattened section's file name in ``root/flatlib`` (written once), or None."""
    body = flat_section(str(inc.file), inc.section, str(inc.folder))
    if body is None:
        return None
    name = _file_name(body)
    target = root / LINK / name
    with _LOCK:
        if path_kind(target) != "file":
            target.parent.mkdir(exist_ok=True)
            write_atomic(target, body.encode("latin-1"))
    return name


@lru_cache(maxsize=32)
def _file_name(body: str) -> str:
    """The flattened file's name: its content's hash (hashed once per body, not per deck)."""
    return hashlib.sha256(body.encode("latin-1")).hexdigest()[:20] + ".lib"


_FLAT: dict = {}  # (file, section, folder) -> (stamps of every file read, body or None)


def flat_section(path: str, section: str, folder: str) -> str | None:
    """The lines of ``section`` of the library file ``path`` with every nested reference
    expanded as ngspice does, or None when it holds anything not reproduced exactly.
    Kept per process while none of the files it read has changed (size, mtime, as
    stated before each was read)."""
    key = (path, section, folder)
    hit = _FLAT.get(key)
    if hit is not None and hit[0] == tuple(file_stamp(f) for f, *_ in hit[0]):
        return hit[1]
    first, read = file_stamp(path), {}
    try:
        lines = _expand(Path(path).resolve(), section, Path(folder).resolve(), 0, read)
        names = [f.lower() for f in read]
        if len(set(names)) != len(names):
            raise _NotFlat("two files whose names differ only in case (ngspice takes them as one)")
        body = f"* {Path(path).name} section {section}, flattened by pixelkit\n" + "\n".join(lines) + "\n"
    except _NotFlat:
        body = None
    _FLAT[key] = ((first, *read.values()), body)  # the name as given too: a link may be repointed
    return body


def _fold(name: str) -> str:
    if not name.isascii():
        raise _NotFlat("a section name outside ASCII (ngspice folds only ASCII case)")
    return name.lower()


def _expand(file: Path, section: str, root: Path, depth: int, read: dict) -> list[str]:
    if depth > _DEPTH:
        raise _NotFlat("reference cycle")
    if not file.is_relative_to(root) or path_kind(file) != "file":
        raise _NotFlat("a file outside the model folder, or missing")
    stamp = read.setdefault(str(file), file_stamp(str(file)))  # stated before the read
    body = _sections_of(*stamp).get(_fold(section))
    if body is None:
        raise _NotFlat("no such section")
    out = []
    for line in body:
        ref = _REFERENCE.match(line)
        if ref:
            name = next(g for g in ref.groups()[:3] if g)
            out += _expand((file.parent / name).resolve(), ref.group(4), root, depth + 1, read)
        elif _LIB_OR_ENDL.match(line):
            raise _NotFlat("a .lib line that is not 'FILE SECTION'")
        else:
            out.append(line)
    return out


@lru_cache(maxsize=16)
def _sections_of(path: str, _size: int, _mtime_ns: int) -> dict:
    """Section name -> its lines, read as bytes and split at newlines only (as ngspice
    does). Refused (None for the caller): anything whose reading ngspice does differently
    or that the kit does not run - an include, a control block, a ``@`` line, a ``\\``
    line ending, a stray carriage return, a continuation of a ``.lib`` or ``.endl`` line,
    a ``.lib`` / ``.endl`` line of another shape."""
    if _size < 0:
        raise _NotFlat("unreadable file")
    try:
        raw = read_bytes(path, "model file", "model").decode("latin-1")
    except (OSError, FileRefused):
        raise _NotFlat("unreadable file") from None
    sections, name, body, after_lib = {}, None, [], False
    for line in raw.split("\n"):
        line = line[:-1] if line.endswith("\r") else line
        if _REFUSED.match(line) or "\r" in line or line.rstrip(" \t").endswith("\\\\"):
            raise _NotFlat("an include, control block, '@', '\\\\' or carriage return")
        if _CONTINUATION.match(line) and after_lib:
            raise _NotFlat("a continuation of a .lib or .endl line")
        if not _COMMENT_OR_BLANK.match(line):
            after_lib = bool(_LIB_OR_ENDL.match(line))
        if name is None:
            define = _DEFINE.match(line)
            if define:
                name, body = _fold(define.group(1)), []
            elif _LIB_OR_ENDL.match(line) and not _REFERENCE.match(line):
                raise _NotFlat("a .lib or .endl line of another shape")
        elif _ENDL.match(line):
            if name in sections:
                raise _NotFlat("a section defined twice")
            sections[name] = body
            name = None
        elif _DEFINE.match(line):
            raise _NotFlat("section definition inside a section")
        else:
            body.append(line)
    if name is not None:
        raise _NotFlat("section without .endl")
    return sections
