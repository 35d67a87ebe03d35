"""Model-library sections flattened once per process, so a run does not re-read the library.

A deck names its corner as ``.lib "models/sm141064.ngspice" typical``. ngspice
then reads and pre-processes the whole 1.3 MB, 47,000-line GF180 file (it opens it
once), not only the ~8,000 lines the corner's nested references select: 0.04 -
0.08 s of each deck's start-up, measured here on ngspice 39 (0.24 vs 0.32 s for the
dual-pixel bench), some 10 % of a whole-chip frame's CPU time and more of a small
deck's.

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
resolved from the folder of the file that holds it; section names compare
without case; a section ends at the first ``.endl`` (its name is not checked:
GF180's ``.LIB dio`` ends with ``.endl diode``). Anything this module does not
reproduce exactly - an ``.include`` inside a section (its path would be resolved
from another folder), a reference leaving the model folder, a missing file or
section, a reference cycle, a section defined twice, a ``.lib`` line
with more than a file and a section - leaves the deck's own ``.lib`` line in place, so
ngspice reads the library itself as before (and reports what is wrong with it).

Independent check (``tests/test_flatlib.py``): decks of every corner, of the
Monte Carlo mismatch include and of the AFE give bit-identical raw vectors
with the flattened include and with ngspice's own ``.lib`` processing.
"""
from __future__ import annotations

import hashlib
import os
import re
import threading
from functools import lru_cache
from pathlib import Path

from ..fileio import path_kind, write_atomic
from ..tech.modellib import Include

LINK = "flatlib"
_DEFINE = re.compile(r"^[ \t]*\.lib[ \t]+([^\s'\"]+)[ \t]*$", re.I)
_REFERENCE = re.compile(r"""^[ \t]*\.lib[ \t]+(?:'([^']+)'|"([^"]+)"|(\S+))[ \t]+(\S+)[ \t]*$""", re.I)
_ENDL = re.compile(r"^[ \t]*\.endl\b", re.I)
_INCLUDE = re.compile(r"^[ \t]*\.inc", re.I)
_ANY_LIB = re.compile(r"^[ \t]*\.lib\b", re.I)
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
    data = body.encode("latin-1")
    name = hashlib.sha256(data).hexdigest()[:20] + ".lib"
    target = root / LINK / name
    with _LOCK:
        if path_kind(target) != "file":
            target.parent.mkdir(exist_ok=True)
            write_atomic(target, data)
    return name


_FLAT: dict = {}  # (file, section, folder) -> (stamps of every file read, body or None)


def flat_section(path: str, section: str, folder: str) -> str | None:
    """The lines of ``section`` of the library file ``path`` with every nested reference
    expanded as ngspice does, or None when it holds anything not reproduced exactly.
    Kept per process while none of the files it read has changed (size, mtime)."""
    key = (path, section.lower(), folder)
    hit = _FLAT.get(key)
    if hit is not None and hit[0] == _stamps(f for f, *_ in hit[0]):
        return hit[1]
    read: list = []
    try:
        lines = _expand(Path(path), section, Path(folder).resolve(), 0, read)
        body = f"* {Path(path).name} section {section}, flattened by pixelkit\n" + "\n".join(lines) + "\n"
    except _NotFlat:
        body = None
    _FLAT[key] = (_stamps(dict.fromkeys([path, *read])), body)
    return body


def _stamps(files) -> tuple:
    out = []
    for f in files:
        try:
            st = os.stat(f)
            out.append((f, st.st_size, st.st_mtime_ns))
        except OSError:
            out.append((f, -1, -1))
    return tuple(out)


def _expand(file: Path, section: str, root: Path, depth: int, read: list) -> list[str]:
    if depth > _DEPTH:
        raise _NotFlat("reference cycle")
    read.append(str(file))
    sections = _sections(file)
    if section.lower() not in sections:
        raise _NotFlat("no such section")
    out = []
    for line in sections[section.lower()]:
        if _INCLUDE.match(line):
            raise _NotFlat("include inside a section")
        ref = _REFERENCE.match(line)
        if _ANY_LIB.match(line) and not ref:
            raise _NotFlat("a .lib line that is not 'FILE SECTION'")
        if ref:
            name = next(g for g in ref.groups()[:3] if g)
            nested = (file.parent / name).resolve()
            if not nested.is_relative_to(root) or path_kind(nested) != "file":
                raise _NotFlat("reference outside the model folder")
            out += _expand(nested, ref.group(4), root, depth + 1, read)
        else:
            out.append(line)
    return out


@lru_cache(maxsize=16)
def _sections_of(path: str, _size: int, _mtime_ns: int) -> dict:
    sections, name, body = {}, None, []
    for line in Path(path).read_text(encoding="latin-1").splitlines():
        if name is None:
            m = _DEFINE.match(line)
            if m:
                name, body = m.group(1).lower(), []
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


def _sections(file: Path) -> dict:
    try:
        st = file.stat()
        return _sections_of(str(file), st.st_size, st.st_mtime_ns)
    except OSError:
        raise _NotFlat("unreadable file") from None
