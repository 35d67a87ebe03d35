"""Which fields of a design a computation reads: the extraction cache keys on those (``overlay._key``), so a
change the drawing never sees (a bias voltage, a timing, a spec) finds the extraction it already has.

``reading(design)`` is a context manager: while it is open, every read of a field of the design's dataclasses
(``design.pixel.devices.tg_w``) is recorded by its path (``("pixel", "devices", "tg_w")``); a read that
returns another of the design's dataclasses is no read of its own (what is read inside it is). Whatever takes
an object whole (its ``__dict__``, ``__reduce_ex__`` for a copy or a pickle) records the whole object, and
``dataclasses.replace``, ``==`` and ``hash`` read every field by name: the trace errs towards reading more,
never less. ``values(design, paths)`` gives what the design holds at those paths, the key's part.

The read set may depend on the values read (a boosted gate drive reads ``v_gate``): the cache keeps each
read set it met and a design finds its entry under any of them whose values it shares (the values of a read
set decide every branch the drawing takes, so the same values read the same fields).
"""
from __future__ import annotations

import dataclasses
import threading
from contextlib import contextmanager

_WHOLE = ("__dict__", "__reduce_ex__", "__reduce__", "__getstate__")
_LOCK = threading.RLock()    # one trace at a time: the classes are patched for every thread (the report's
                             # prefetch threads); another thread's reads of the same objects are recorded too


def _walk(obj, path, out, skip):
    """{id: (object, [paths])} of the dataclass instances under ``obj`` (tuples and lists entered)."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        entry = out.setdefault(id(obj), (obj, []))
        entry[1].append(path)
        if len(entry[1]) > 1:
            return
        for f in dataclasses.fields(obj):
            if path == () and f.name in skip:
                continue
            _walk(object.__getattribute__(obj, f.name), path + (f.name,), out, skip)
    elif isinstance(obj, (tuple, list)):
        for k, v in enumerate(obj):
            _walk(v, path + (k,), out, skip)


@contextmanager
def reading(design, skip=()):
    """Record the fields of ``design`` read inside the block: yields the set of paths (filled as it runs).
    ``skip``: top-level fields not traced (keyed whole by the caller: the technology)."""
    objs: dict = {}
    _walk(design, (), objs, set(skip))
    classes = {type(o) for o, _p in objs.values()}
    names = {c: {f.name for f in dataclasses.fields(c)} for c in classes}
    reads: set = set()

    def traced(self, name, _get=object.__getattribute__):
        value = _get(self, name)
        entry = objs.get(id(self))
        if entry is not None and entry[0] is self:
            if name in names[type(self)]:
                inner = objs.get(id(value))
                if inner is None or inner[0] is not value:
                    reads.update(p + (name,) for p in entry[1])
            elif name in _WHOLE:
                reads.update(entry[1])
        return value
    with _LOCK:
        saved = {c: c.__dict__.get("__getattribute__") for c in classes}
        for c in classes:
            c.__getattribute__ = traced
        try:
            yield reads
        finally:
            for c, old in saved.items():
                if old is None:
                    del c.__getattribute__
                else:
                    c.__getattribute__ = old


def value_at(design, path):
    obj = design
    for step in path:
        obj = obj[step] if isinstance(step, int) else object.__getattribute__(obj, step)
    return obj


def values(design, paths) -> str:
    """The design's values at ``paths`` (sorted), as one string for a cache key (``repr``: floats exactly); a
    path the design no longer has reads as missing."""
    out = []
    for p in sorted(paths, key=repr):
        try:
            out.append((p, value_at(design, p)))
        except (AttributeError, IndexError, TypeError):
            out.append((p, "<missing>"))
    return repr(out)
