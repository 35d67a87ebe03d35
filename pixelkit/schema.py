"""Declarative, validating loading of TOML tables into frozen dataclasses.

A field is declared with :func:`qty`, :func:`num`, :func:`integer`, :func:`text`,
:func:`ident`, :func:`flag` or :func:`table`; :func:`load` walks a mapping and
builds the dataclass, refusing a missing field, an unknown field, a wrong unit or
a value outside its range with a :class:`ConfigError` naming the field path and
echoing the value as the user wrote it.

Every quantity also has a *plausibility range* (``plausible=(lo, hi)`` in SI,
kept in the field's metadata so the design-file reference shows it): the span a
real chip, lens or scene could have. A value outside it (``"1e-300 V"``,
``"1e300 fF"``) is refused rather than turned into a figure no chip has.
"""
from __future__ import annotations

import dataclasses
import inspect
import math
import re
import tomllib
from pathlib import Path
from typing import Any

from .errors import MISSING, ConfigError
from .units import quantity, si_text

IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]{0,63}$")
#: A dotted key of a file (``pixel.devices.rst_w``): names joined by dots, at most 8 parts.
DOTTED = re.compile(r"^[A-Za-z_][A-Za-z0-9_]{0,63}(\.[A-Za-z_][A-Za-z0-9_]{0,63}){0,7}$")
_NODEFAULT = dataclasses.MISSING


def _field(kind: str, default=_NODEFAULT, doc: str = "", **meta):
    meta.update(kind=kind, doc=doc)
    if default is _NODEFAULT:
        return dataclasses.field(metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


def qty(dim: str, default=_NODEFAULT, *, gt=None, ge=None, le=None, lt=None, plausible=None, doc=""):
    """A physical quantity in SI, written with a unit in the file; ``plausible=(lo, hi)`` in SI."""
    return _field("qty", default, doc, dim=dim, gt=gt, ge=ge, le=le, lt=lt, plausible=plausible)


def num(default=_NODEFAULT, *, gt=None, ge=None, le=None, lt=None, plausible=None, unit_required=False,
        doc=""):
    """A dimensionless number (``"60 dB"`` is read as an amplitude ratio).

    ``unit_required``: a bare number is refused as ambiguous (a gain: ``"60 dB"`` or ``"1000 V/V"``).
    """
    return _field("qty", default, doc, dim="1", gt=gt, ge=ge, le=le, lt=lt, plausible=plausible,
                  unit_required=unit_required or None)


def integer(default=_NODEFAULT, *, ge=None, le=None, doc=""):
    return _field("int", default, doc, ge=ge, le=le)


def text(default=_NODEFAULT, *, choices=None, doc=""):
    return _field("str", default, doc, choices=choices)


def ident(default=_NODEFAULT, doc=""):
    """A name that may reach a netlist: letters, digits and '_' only."""
    return _field("ident", default, doc)


def flag(default=_NODEFAULT, doc=""):
    return _field("bool", default, doc)


def items(inner, default=_NODEFAULT, *, min_len=1, max_len=64, doc=""):
    """A TOML array whose elements are each read as ``inner`` (a field made by :func:`qty`,
    :func:`num`, :func:`ident`, ...); loaded as a tuple."""
    return _field("list", default, doc, item=dict(inner.metadata), min_len=min_len, max_len=max_len)


def limit(default=None, doc="", of: str = "figure"):
    """A quantity whose dimension another field decides (a spec limit, in its figure's unit; ``of``:
    what decides it, for the reference): a string with a unit, or a plain number; the table's
    ``validate`` (or its checker) converts it."""
    return _field("limit", default, doc, of=of)


def named(cls, doc="", keys: str = "ident", pair: tuple | None = None):
    """A table of named tables (``[spec.<name>]``), each loaded into ``cls``, whose ``name``
    field receives the table's name; loaded as a tuple in file order (empty when absent).

    ``keys="dotted"``: the names are dotted keys (``"pixel.sf_bias"``, each part a name);
    ``pair=("min", "max")``: an entry may also be a two-item list, read as those two fields
    (``"pixel.sf_bias" = ["600 nA", "1.5 uA"]``)."""
    return dataclasses.field(default=(), metadata=dict(kind="map", cls=cls, doc=doc, keys=keys, pair=pair))


def table(cls, default=_NODEFAULT, doc=""):
    """A nested table loaded into ``cls``; ``default=None`` makes it optional."""
    if default is not _NODEFAULT and default is not None:
        return dataclasses.field(default_factory=default, metadata=dict(kind="table", cls=cls, doc=doc))
    return _field("table", default, doc, cls=cls)


def check_range(x, meta, path, source, shown):
    """``x`` (SI) within the field's bounds and plausibility range; errors echo ``shown``."""
    dim = meta.get("dim", "1")
    bounds = [("gt", lambda a, b: a > b, ">"), ("ge", lambda a, b: a >= b, ">="),
              ("lt", lambda a, b: a < b, "<"), ("le", lambda a, b: a <= b, "<=")]
    for key, ok, sym in bounds:
        b = meta.get(key)
        if b is not None and not ok(x, b):
            raise ConfigError(source, path, shown, f"a value {sym} {si_text(b, dim)}")
    lo_hi = meta.get("plausible")
    if lo_hi is not None and not lo_hi[0] <= x <= lo_hi[1]:
        raise ConfigError(source, path, shown, f"a value from {si_text(lo_hi[0], dim)} to "
                          f"{si_text(lo_hi[1], dim)} (the range a real chip could have)")
    return x


def _convert(value, meta, path, source):
    kind = meta["kind"]
    if kind == "qty":
        if meta.get("unit_required") and not (isinstance(value, str) and re.search(r"[A-Za-z/%]", value)):
            raise ConfigError(source, path, value, "a value with its unit, like '60 dB' or '1000 V/V' "
                              "(a bare number is ambiguous: a ratio or decibels?)")
        x = quantity(value, meta["dim"], path, source)
        return check_range(x, meta, path, source, value)
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(source, path, value, "a whole number")
        return check_range(value, meta, path, source, value)
    if kind == "str":
        if not isinstance(value, str):
            raise ConfigError(source, path, value, "a string")
        choices = meta.get("choices")
        if choices and value not in choices:
            raise ConfigError(source, path, value, f"one of {', '.join(choices)}")
        return value
    if kind == "ident":
        if not isinstance(value, str) or not IDENT.match(value):
            raise ConfigError(source, path, value,
                              "a name of letters, digits and '_' (starting with a letter, at most 64)")
        return value
    if kind == "bool":
        if not isinstance(value, bool):
            raise ConfigError(source, path, value, "true or false")
        return value
    if kind == "table":
        return load(meta["cls"], value, path, source)
    if kind == "list":
        return _convert_list(value, meta, path, source)
    if kind == "limit":
        ok = isinstance(value, str) and 0 < len(value) <= 64 or (
            isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value))
        if not ok:
            raise ConfigError(source, path, value, "a quantity with its unit, like '5 uV/e-' or '30 e-'")
        return value
    if kind == "map":
        return _convert_map(value, meta, path, source)
    raise AssertionError(kind)


def _convert_list(value, meta, path, source) -> tuple:
    item, lo, hi = meta["item"], meta["min_len"], meta["max_len"]
    if not isinstance(value, list):
        raise ConfigError(source, path, value, f"a list of {lo} to {hi} values, each {_describe(item)}")
    if not lo <= len(value) <= hi:
        raise ConfigError(source, path, f"{len(value)} items", f"a list of {lo} to {hi} items")
    out = tuple(_convert(v, item, f"{path}[{i}]", source) for i, v in enumerate(value))
    if len(set(out)) != len(out):
        raise ConfigError(source, path, value, "a list without repeated values")
    return out


#: Most named tables (specs) one file may hold.
MAX_NAMED = 200


def _convert_map(value, meta, path, source) -> tuple:
    if not isinstance(value, dict):
        raise ConfigError(source, path, value, f"a table of named tables, like [{path}.<name>]")
    if len(value) > MAX_NAMED:
        raise ConfigError(source, path, f"{len(value)} entries", f"at most {MAX_NAMED} entries")
    out = []
    dotted, pair = meta.get("keys") == "dotted", meta.get("pair")
    if dotted:
        value = _flat(value, {f.name for f in dataclasses.fields(meta["cls"])})
    for key, sub in value.items():
        if not (DOTTED if dotted else IDENT).match(key):
            raise ConfigError(source, f"{path}.{key}", key,
                              "a dotted key of names (letters, digits and '_', each starting with a letter), "
                              "like \"pixel.sf_bias\"" if dotted else
                              "a name of letters, digits and '_' (starting with a letter, at most 64)")
        if pair and isinstance(sub, list):
            if len(sub) != 2:
                raise ConfigError(source, f"{path}.{key}", sub, f"a list of two values [{pair[0]}, {pair[1]}] "
                                  f"or a table with {pair[0]} and {pair[1]}")
            sub = dict(zip(pair, sub))
        obj = load(meta["cls"], sub, f"{path}.{key}", source)
        out.append(dataclasses.replace(obj, name=key))
    return tuple(out)


def _flat(value: dict, fields: set, prefix: str = "") -> dict:
    """Entries of a table keyed by dotted keys, also when written unquoted (TOML nests
    ``pixel.sf_bias = [...]`` as ``{"pixel": {"sf_bias": [...]}}``): a table none of whose keys
    is a field of the entry is a level of the key."""
    out = {}
    for key, sub in value.items():
        name = f"{prefix}{key}"
        if isinstance(sub, dict) and sub and not set(sub) & fields and prefix.count(".") < 8:
            out.update(_flat(sub, fields, name + "."))
        else:
            out[name] = sub
    return out


def load(cls, mapping, path: str = "", source: str = ""):
    """Build ``cls`` from ``mapping``; every refusal names ``path.field``."""
    if not isinstance(mapping, dict):
        raise ConfigError(source, path or "(top level)", mapping, "a table")
    known = {f.name: f for f in dataclasses.fields(cls) if f.metadata.get("kind", "skip") != "skip"}
    unknown = sorted(set(mapping) - set(known))
    if unknown:
        where = f"{path}.{unknown[0]}" if path else unknown[0]
        raise ConfigError(source, where, mapping[unknown[0]],
                          f"no such field here; allowed: {', '.join(sorted(known))}")
    values = {}
    for name, f in known.items():
        sub = f"{path}.{name}" if path else name
        if name in mapping:
            values[name] = _convert(mapping[name], f.metadata, sub, source)
        elif f.default is _NODEFAULT and f.default_factory is _NODEFAULT:
            raise ConfigError(source, sub, MISSING, _describe(f.metadata))
    obj = cls(**values)
    check = getattr(obj, "validate", None)
    if check is not None:
        if len(inspect.signature(check).parameters) >= 3:
            check(path, source, mapping)  # the raw table, to echo values as written
        else:
            check(path, source)
    return obj


def as_written(raw, dotted: str, fallback):
    """The value at ``dotted`` (``"primary.pd_width"``) of a raw TOML mapping, as the user wrote it."""
    node = raw
    for part in dotted.split("."):
        if not isinstance(node, dict) or part not in node:
            return fallback
        node = node[part]
    return node


def _describe(meta) -> str:
    kind = meta["kind"]
    if kind == "qty":
        from .units import DIMENSIONS
        return f"a quantity like '{DIMENSIONS[meta['dim']][1]}'"
    if kind == "list":
        return f"a list of values, each {_describe(meta['item'])}"
    return {"int": "a whole number", "str": "a string", "ident": "a name",
            "bool": "true or false", "table": "a table", "map": "a table of named tables",
            "limit": "a quantity in the figure's unit"}[kind]


def read_toml(path: Path, what: str) -> dict:
    """Read a TOML file (UTF-8, a byte-order mark allowed), turning every I/O, decode and
    syntax failure into one line naming the file and what is wrong. The file is read with a
    bound (:mod:`pixelkit.readfile`): a pipe, a device or a file larger than any design is
    refused before it is read."""
    from .readfile import read_text
    text_ = read_text(Path(path), what, "technology" if what == "technology" else "design")
    try:
        return tomllib.loads(text_)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(str(path), what, str(exc), "valid TOML") from None
    except RecursionError:
        raise ConfigError(str(path), what, "nesting too deep", "valid TOML of sensible depth") from None


_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


def _toml_string(v: str) -> str:
    """A TOML basic string: backslash, quote and every control character escaped."""
    out = []
    for c in v:
        if c in '"\\':
            out.append("\\" + c)
        elif ord(c) < 0x20 or ord(c) == 0x7F or c in "\u2028\u2029\x85":
            out.append(f"\\u{ord(c):04X}")
        else:
            out.append(c)
    return '"' + "".join(out) + '"'


def _toml_key(k: str) -> str:
    return k if _BARE_KEY.match(k) else _toml_string(k)


def to_toml(data: dict[str, Any]) -> str:
    """Write a nested dict of strings, numbers, booleans and lists as TOML."""
    lines: list[str] = []

    def scalar(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (int, float)):
            return repr(v)
        if isinstance(v, str):
            return _toml_string(v)
        if isinstance(v, list):
            return "[" + ", ".join(scalar(x) for x in v) + "]"
        raise TypeError(f"cannot write {type(v).__name__} to TOML")

    def emit(table: dict, prefix: str):
        for k, v in table.items():
            if not isinstance(v, dict):
                lines.append(f"{_toml_key(k)} = {scalar(v)}")
        for k, v in table.items():
            if isinstance(v, dict):
                name = f"{prefix}.{_toml_key(k)}" if prefix else _toml_key(k)
                lines.append("")
                lines.append(f"[{name}]")
                emit(v, name)

    emit(data, "")
    return "\n".join(lines).lstrip("\n") + "\n"
