"""Reading a GDS file: one checked way for every GDS the kit reads (issue 44).

A design's ``[layout] gds`` (and any GDS a user hands the kit) is checked before a reader sees
it: a regular file within the ``gds`` bound (``readfile``: a pipe or a device would block or
fill memory), a whole GDSII stream (its HEADER record first, its ENDLIB record last: the check
``pixelkit signoff`` makes, ``signoff/gds_in.py``) - an empty, random or truncated file, a
compressed one (gzip, which KLayout would expand without a bound; ``signoff`` expands it with a
bound, these readers do not) or an OASIS file are refused by name - and a file the reader still
cannot read (damaged records) is refused naming the reader's own message. Each refusal is a
:class:`~pixelkit.errors.ConfigError` (exit 2) naming the field, the file and what is allowed.
"""
from __future__ import annotations

from pathlib import Path

from ..errors import ConfigError
from ..readfile import read_bytes

ALLOWED = "a GDSII stream file (uncompressed, as KLayout or gdstk write it)"
_MAGIC = ((b"\x1f\x8b", "gzip-compressed (decompress it first: a compressed GDS is not expanded by the kit)"),
          (b"%SEMI-OASIS", "an OASIS file"), (b"PK\x03\x04", "a zip archive"))


def check_gds(path, field: str = "layout.gds") -> Path:
    """``path`` if it holds a whole GDSII stream (``signoff.gds_in.stream_kind``: its HEADER record
    first, its ENDLIB record last); else a ConfigError naming ``field``, the file and why."""
    from .signoff.gds_in import stream_kind
    path = Path(path)
    data = read_bytes(path, field, "gds")
    for magic, what in _MAGIC:
        if data.startswith(magic):
            raise ConfigError(str(path), field, what, ALLOWED)
    try:
        stream_kind(path, data)
    except ConfigError as exc:
        raise ConfigError(str(path), field, exc.value, ALLOWED) from None
    return path


def read_gdstk(path, field: str = "layout.gds"):
    """The ``gdstk.Library`` of a checked GDS."""
    import gdstk
    check_gds(path, field)
    try:
        return gdstk.read_gds(str(path))
    except (OSError, RuntimeError, ValueError) as exc:
        raise ConfigError(str(path), field, f"a truncated or damaged GDS (gdstk: {exc})", ALLOWED) from None


def read_klayout(path, field: str = "layout.gds", layout=None):
    """The ``klayout.db.Layout`` of a checked GDS (read into ``layout`` when given)."""
    import klayout.db as kdb
    check_gds(path, field)
    layout = kdb.Layout() if layout is None else layout
    try:
        layout.read(str(path))
    except (OSError, RuntimeError, ValueError) as exc:
        text = " ".join(str(exc).split())[:200]
        raise ConfigError(str(path), field, f"a truncated or damaged GDS (KLayout: {text})", ALLOWED) from None
    return layout
