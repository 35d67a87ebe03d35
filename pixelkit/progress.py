"""Progress of anything that runs longer than a couple of seconds, on stderr (tqdm).

Three modes (:func:`mode`):

- ``bar``: a tqdm bar, when stderr is a terminal (or ``PIXELKIT_PROGRESS=1``);
- ``lines``: plain lines for a log or a CI job, when stderr is not a terminal (or
  ``PIXELKIT_PROGRESS=lines``): one line when a bar starts, when its stage changes, at
  most every ``LINE_EVERY_S`` seconds while it runs, and one when it ends, never a
  carriage return;
- ``quiet``: nothing, with ``--quiet`` or ``--json`` (the CLI calls :func:`set_quiet`) or
  ``PIXELKIT_PROGRESS=0``.

``progress(iterable, total=..., desc=...)`` wraps an iterable (or counts by hand with
``total``); ``step(desc)`` is a context manager for one long step without an iterable (an
indeterminate bar). A command shows *one* bar: :func:`command_bar` opens it, and every bar
the library opens while it is open stays silent (the SPICE batches of a report, the points
of a sweep inside a report section), so the terminal or the log reads as one progress line
per command.
"""
from __future__ import annotations

import os
import sys
import threading
import time
from contextlib import contextmanager

_QUIET = False
_COMMAND_BARS = 0
_BARS_LOCK = threading.Lock()   # a report builds a section while its sign-off runs in another thread
#: Lines mode: at most one line per this many seconds while the description stays the same.
LINE_EVERY_S = 10.0


def set_quiet(quiet: bool = True) -> None:
    """Silence (or re-enable) every progress bar of this process."""
    global _QUIET
    _QUIET = bool(quiet)


def mode() -> str:
    """``quiet``, ``bar`` or ``lines`` (see the module docstring)."""
    env = os.environ.get("PIXELKIT_PROGRESS", "")
    if env == "0" or _QUIET:
        return "quiet"
    if env == "1":
        return "bar"
    if env == "lines":
        return "lines"
    try:
        return "bar" if sys.stderr.isatty() else "lines"
    except (AttributeError, ValueError):
        return "lines"


def enabled() -> bool:
    return mode() != "quiet"


def _tqdm():
    from tqdm.auto import tqdm
    return tqdm


class _NoCarriageReturn:
    """stderr for the lines mode: tqdm's lone carriage returns dropped."""

    def __init__(self, stream):
        self.stream = stream

    def write(self, s):
        s = s.replace("\r", "")
        if s:
            self.stream.write(s)

    def flush(self):
        self.stream.flush()


def _line_bar_class():
    from tqdm import tqdm

    class LineBar(tqdm):
        """A tqdm whose display is a new line when the stage changes or LINE_EVERY_S has passed."""

        def display(self, msg=None, pos=None):
            if msg == "":          # close() clearing the bar: say it ended instead
                if not getattr(self, "_ended", False):
                    self._ended = True
                    count = self._count()
                    ended = "stopped at" if self.total and self.n < self.total else "done"
                    self.fp.write(f"{self.desc or 'progress'}: {ended} {count + ' ' if count else ''}in "
                                  f"{self.format_interval(self.format_dict['elapsed'])}\n")
                    self.fp.flush()
                return None        # no trailing carriage return
            now = time.monotonic()
            last_desc, last_t = getattr(self, "_last_line", (None, -1e9))
            if self.desc == last_desc and now - last_t < LINE_EVERY_S:
                return None
            self._last_line = (self.desc, now)
            self.fp.write(self.__str__().strip().replace(", ~? left", "") + "\n")   # no rate yet: no estimate
            self.fp.flush()
            return None

        def set_description(self, desc=None, refresh=True):
            self.set_description_str(desc, refresh)   # tqdm's would append ": " to the line's name

        def _count(self) -> str:
            if self.total is None and self.unit == "s":   # an indeterminate step: its time says it all
                return ""
            unit = self.unit if self.unit != "it" else ""
            n = f"{self.n}/{self.total}" if self.total else f"{self.n}"
            return f"{n} {unit}".strip()

    return LineBar


def _bar(iterable, total, desc, unit, eta: bool = True, **kw):
    silent = mode() == "quiet" or _COMMAND_BARS > 0
    m = mode()
    if m == "lines" and not silent:
        known = total is not None or hasattr(iterable, "__len__")
        fmt = kw.pop("bar_format", None) or (("{desc}: {n_fmt}/{total_fmt} {unit} [{elapsed}, ~{remaining} left]{postfix}"
                                              if eta else "{desc}: {n_fmt}/{total_fmt} {unit} [{elapsed}]{postfix}")
                                             if known
                                             else "{desc}: {n_fmt} {unit} [{elapsed}]{postfix}")
        return _line_bar_class()(iterable, total=total, desc=desc, unit=unit, leave=False,
                                 file=_NoCarriageReturn(sys.stderr), mininterval=LINE_EVERY_S,
                                 bar_format=fmt, **kw)
    if not eta and total is not None:   # counted items of unequal cost: no time estimate from their rate
        kw.setdefault("bar_format", "{desc}: {n_fmt}/{total_fmt} {unit} |{bar}| [{elapsed}]{postfix}")
    return _tqdm()(iterable, total=total, desc=desc, unit=unit, disable=silent, leave=False,
                   file=sys.stderr, dynamic_ncols=True, **kw)


def progress(iterable=None, total: int | None = None, desc: str = "", unit: str = "run", **kw):
    """A bar over ``iterable`` (or a manual bar with ``total``); silent inside a command bar."""
    return _bar(iterable, total, desc, unit, **kw)


@contextmanager
def command_bar(desc: str, total: int | None = None, unit: str = "step", eta: bool = True):
    """The one bar of a command: every other bar opened while it is open stays silent (so a
    command bar opened inside another, a sweep's inside a report section, is silent too).
    ``eta``: show the time left from the rate (off where the items' costs differ widely)."""
    global _COMMAND_BARS
    bar = _bar(None, total, desc, unit, eta)
    with _BARS_LOCK:
        _COMMAND_BARS += 1
    try:
        yield bar
    finally:
        with _BARS_LOCK:
            _COMMAND_BARS -= 1
        bar.close()


@contextmanager
def step(desc: str):
    """An indeterminate bar for one long step; closes when the block ends."""
    bar = progress(total=None, desc=desc, unit="s", bar_format="{desc}: {elapsed}")
    done = threading.Event()

    def tick():
        while not done.wait(0.5):
            bar.refresh()

    ticker = threading.Thread(target=tick, daemon=True)
    if not bar.disable:
        ticker.start()
    try:
        yield bar
    finally:
        done.set()
        bar.close()
