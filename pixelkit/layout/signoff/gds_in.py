"""A layout someone else drew, checked before any deck runs on it (``pixelkit signoff``).

Each refusal is exit 2 and names the file and what is wrong:

- the file: not a regular file, empty, larger than a layout of this kit's scale could be
  (``readfile``'s ``gds`` bound), gzip-compressed beyond that bound once expanded (a compression
  bomb is refused while it is expanded, never written out), not GDSII or OASIS (KLayout reads DXF,
  CIF, LEF/DEF ... too: the kit signs off what the foundry takes), a GDSII stream that stops before
  its ENDLIB record (truncated), or one KLayout cannot read (its message);
- the cells: none, several top cells without ``--top``, a ``--top`` that is not a cell;
- the layers: a layer / datatype with shapes that the technology does not map (``[layers]``: the
  decks and the extraction would ignore it silently);
- the labels: a text on a label layer (``metalN_label``) that lies on no shape of its metal (it
  names no net: a pin the designer thinks is there is not).

The checked layout is handed on as a copy in a private folder (expanded where it was compressed),
so every deck reads exactly the bytes that were checked.
"""
from __future__ import annotations

import zlib
from dataclasses import dataclass
from pathlib import Path

from ...errors import ConfigError

GDS_HEADER = b"\x00\x06\x00\x02"
GDS_ENDLIB = b"\x00\x04\x04\x00"
OASIS_MAGIC = b"%SEMI-OASIS\r\n"


@dataclass
class CheckedLayout:
    path: Path              # the checked copy (GDSII or OASIS), in the caller's private folder
    source: str             # the file the user named
    top: str
    layout: object          # klayout.db.Layout
    cells: list


def _refuse(path, what: str, found: str, allowed: str) -> ConfigError:
    return ConfigError(str(path), what, found, allowed)


def _expanded(path, data: bytes, limit: int) -> bytes:
    """``data`` gunzipped, refused as soon as it passes ``limit`` bytes."""
    d = zlib.decompressobj(16 + zlib.MAX_WBITS)
    out, chunk = [], data
    total = 0
    try:
        while chunk:
            part = d.decompress(chunk, limit + 1 - total)
            total += len(part)
            out.append(part)
            if total > limit:
                raise _refuse(path, "layout", f"gzip data expanding past {limit >> 20} MiB",
                              f"a layout of at most {limit >> 20} MiB once expanded (a compression bomb?)")
            chunk = d.unconsumed_tail
        out.append(d.flush())
    except zlib.error as exc:
        raise _refuse(path, "layout", f"damaged gzip data ({exc})", "a GDSII or OASIS file, gzip-compressed "
                      "or not") from None
    if not d.eof:
        raise _refuse(path, "layout", "gzip data that stops before its end (truncated)",
                      "a whole GDSII or OASIS file")
    return b"".join(out)


def stream_kind(path, data: bytes) -> str:
    """"gds" or "oas" for a whole GDSII or OASIS stream (uncompressed); else a refusal naming ``path``."""
    if not data:
        raise _refuse(path, "layout", "an empty file", "a GDSII or OASIS file")
    if data.startswith(GDS_HEADER):
        end = data.rfind(GDS_ENDLIB)    # GDSII may pad the stream to whole blocks with zeros after it
        if end < 0 or data[end + 4:].strip(b"\x00"):
            raise _refuse(path, "layout", f"a GDSII stream that stops after {len(data)} bytes without its "
                          "ENDLIB record (truncated)", "a whole GDSII file")
        return "gds"
    if data.startswith(OASIS_MAGIC):
        return "oas"
    shown = data[:16].hex(" ")
    raise _refuse(path, "layout", f"a file starting with bytes {shown}", "a GDSII file (starting with its HEADER "
                  "record 00 06 00 02) or an OASIS file (%SEMI-OASIS), gzip-compressed or not")


def read_layout(path, tech, top: str | None, folder: Path) -> CheckedLayout:
    """The layout at ``path``, checked, copied into ``folder`` (a private temporary folder)."""
    import klayout.db as kdb
    from ...readfile import LIMITS, read_bytes
    limit = LIMITS["gds"]
    data = read_bytes(path, "layout", "gds")
    if data[:2] == b"\x1f\x8b":
        data = _expanded(path, data, limit)
    kind = stream_kind(path, data)
    copy = Path(folder) / f"layout.{kind}"
    copy.write_bytes(data)
    layout = kdb.Layout()
    try:
        layout.read(str(copy))
    except RuntimeError as exc:
        msg = str(exc).split(" in Layout.read")[0]
        raise _refuse(path, "layout", f"a file KLayout cannot read ({msg})", "a readable GDSII or OASIS file") from None
    names = sorted(c.name for c in layout.each_cell())
    tops = sorted(c.name for c in layout.top_cells())
    if not names:
        raise _refuse(path, "cells", "(none)", "a layout with its cells")
    if top is None:
        if len(tops) != 1:
            raise _refuse(path, "--top", "(not given)", f"one of its top cells, {', '.join(tops[:20])}"
                          + (" ..." if len(tops) > 20 else "") + " (the layout has several)")
        top = tops[0]
    elif layout.cell(top) is None:
        shown = ", ".join(names[:20]) + (" ..." if len(names) > 20 else "")
        raise _refuse(path, "--top", top, f"a cell of the layout ({shown})")
    cell = layout.cell(top)
    _check_layers(path, layout, cell, tech)
    _check_labels(path, layout, cell, tech)
    return CheckedLayout(copy, str(path), top, layout, names)


def _mapped(tech) -> dict:
    """{(layer, datatype): name} of the technology's layers."""
    return {(lay.layer, lay.datatype): name for name, lay in tech.layout.layers.items()}


def _check_layers(path, layout, cell, tech) -> None:
    mapped = _mapped(tech)
    for li in layout.layer_indexes():
        info = layout.get_info(li)
        if (info.layer, info.datatype) in mapped:
            continue
        it = cell.begin_shapes_rec(li)
        if it.at_end():
            continue
        where = it.cell().name
        raise _refuse(path, f"layer {info.layer}/{info.datatype}", f"shapes in cell {where}",
                      f"layers of technology {tech.name} ([layers] of {tech.source}: "
                      + ", ".join(f"{n} {a}/{b}" for (a, b), n in sorted(mapped.items())[:12]) + " ...); a layer the "
                      "technology does not map would be ignored by the extraction and the decks")


def _check_labels(path, layout, cell, tech) -> None:
    import klayout.db as kdb
    for name, lay in tech.layout.layers.items():
        if not name.endswith("_label"):
            continue
        metal = name[: -len("_label")]
        if metal not in tech.layout.layers:
            continue
        li = layout.find_layer(lay.layer, lay.datatype)
        if li is None:
            continue
        mi = layout.find_layer(tech.layer(metal).layer, tech.layer(metal).datatype)
        shapes = kdb.Region(cell.begin_shapes_rec(mi)) if mi is not None else kdb.Region()
        it = cell.begin_shapes_rec(li)
        while not it.at_end():
            s = it.shape()
            if s.is_text():
                t = s.text.transformed(it.trans())
                p = t.trans.disp
                probe = kdb.Region(kdb.Box(p.x - 1, p.y - 1, p.x + 1, p.y + 1))
                if (probe & shapes).is_empty():
                    raise _refuse(path, f"label {t.string!r}", f"on {name} at ({p.x * layout.dbu:g}, "
                                  f"{p.y * layout.dbu:g}) um of cell {cell.name}, over no {metal} shape",
                                  f"a label placed on a shape of {metal} (it names that shape's net)")
            it.next()
