"""DRC with the technology's own deck, run by KLayout in batch mode (Debian's ``klayout -b``).

The deck is the judge: the kit only runs it and reads its report, a KLayout marker
database (XML, one ``<category>`` per rule, one ``<item>`` per violation, each in the
cell where the deck found it - in deep mode the cell of the hierarchy, with cell-local
coordinates). No user string reaches the command line: the switches come from the
technology file (checked to be plain tokens), the paths are the kit's own.

The deck runs through ``deck_runner.drc``, which evaluates its text unchanged with one
difference outside the rules: the GF180MCU deck's log line asks the shell for the memory in
use (``pmap``) 600+ times, most of a small run's time; the runner answers it from /proc. A deck
with KLayout ``%include`` lines (resolved by KLayout's own loader only) is run directly.

Only a deck pinned by its sha256 runs (``decks.py``). KLayout works in a private folder the kit
makes inside the output folder and its report and log are renamed into place when it has
finished (:func:`klayout_run`); it dies with the kit (:mod:`pixelkit.children`).

A run asked with ``cache=True`` (the report's layout sign-off) is kept in the kit's checked store
(``$PIXELKIT_CACHE/drc``, :mod:`pixelkit.cachestore`) under a key of everything the deck's verdict
depends on: the GDS file's bytes, the top cell, the deck's and the runner's bytes, the deck's
options and KLayout's version (not the thread count, not any path). A second run on the same
drawing gets the deck's own report back (byte for byte; the runner's path it names is this
checkout's) and the log of the run that made it,
headed by a line saying so; ``DrcResult.cached`` says it, ``seconds`` is that run's. A changed
drawing (one byte of the GDS), deck or option runs the deck again.
"""
from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import subprocess
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

from ...errors import PixelkitError
from .deckcache import deck_label
from .decks import drc_deck

RUNNER = Path(__file__).with_name("deck_runner.drc")
KLAYOUT_HINT = "install Debian's klayout (apt-get install klayout; setup.sh does)"


@dataclass(frozen=True)
class Violation:
    rule: str
    description: str
    cell: str
    where: str        # first marker of the rule in that cell (its geometry, cell coordinates in um)
    count: int


@dataclass
class DrcResult:
    deck: str
    top: str
    options: dict
    seconds: float
    klayout: str
    violations: list = field(default_factory=list)
    report: str = ""
    cached: bool = False   # the result of an earlier run on the same drawing (module docstring)

    @property
    def clean(self) -> bool:
        return not self.violations

    @property
    def total(self) -> int:
        return sum(v.count for v in self.violations)

    def by_rule(self) -> dict:
        out: dict = {}
        for v in self.violations:
            out[v.rule] = out.get(v.rule, 0) + v.count
        return out

    def in_cell(self, cell: str) -> dict:
        out: dict = {}
        for v in self.violations:
            if v.cell == cell:
                out[v.rule] = out.get(v.rule, 0) + v.count
        return out

    def as_dict(self) -> dict:
        return {"clean": self.clean, "total": self.total, "by_rule": self.by_rule(), "deck": deck_label(self.deck),
                "top": self.top, "options": self.options, "seconds": round(self.seconds, 2),
                "klayout": self.klayout, "report": self.report,
                "violations": [v.__dict__ for v in self.violations], **({"cached": True} if self.cached else {})}


def klayout_binary() -> str:
    exe = shutil.which("klayout")
    if exe is None:
        raise PixelkitError(f"KLayout is not installed (no `klayout` on PATH): {KLAYOUT_HINT}")
    return exe


def klayout_version() -> str:
    exe = klayout_binary()
    st = os.stat(exe)
    return _version(exe, st.st_size, st.st_mtime_ns)


@lru_cache(maxsize=4)
def _version(exe: str, _size: int, _mtime_ns: int) -> str:
    """KLayout's version, asked once per binary (as it is now: size, mtime)."""
    from ... import children
    p = children.run([exe, "-b", "-v"], capture_output=True, text=True, timeout=60)
    return p.stdout.strip()


def parse_report(path: Path) -> list[Violation]:
    root = ET.parse(path).getroot()
    desc = {}
    for c in root.iter("category"):
        name = c.findtext("name")
        if name:
            desc[name] = (c.findtext("description") or "").strip()
    found: dict = {}
    for item in root.iter("item"):
        rule = (item.findtext("category") or "").strip().strip("'")
        cell = (item.findtext("cell") or "").strip()
        n = int(item.findtext("multiplicity") or 1)
        value = (item.findtext("values/value") or "").strip()
        key = (rule, cell)
        if key in found:
            found[key][1] += n
        else:
            found[key] = [value, n]
    return [Violation(rule, desc.get(rule, ""), cell, where, n) for (rule, cell), (where, n) in sorted(found.items())]


def klayout_run(args_of, workdir: Path, outputs: dict, what: str, cwd: Path | None = None) -> tuple[int, dict]:
    """Run KLayout with the command line ``args_of(stage)`` (every path it writes inside
    ``stage``, a private folder the kit makes in ``workdir``; it works in ``cwd``, default the
    stage), then move each file it wrote into ``workdir`` (``outputs``: name in the stage -> name
    in ``workdir``, ``"log"``: its stdout and stderr; a rename, its place checked first, never
    through a link). Every place is checked before KLayout starts. KLayout dies with the kit
    (:mod:`pixelkit.children`); a killed run's stage is swept by the next run. Returns
    (KLayout's exit status, {name: final path} of the outputs it wrote)."""
    from ... import children, owner
    from ...fileio import check_target, move_into, out_folder, staging_dir
    workdir = out_folder(workdir)
    for name in outputs.values():
        check_target(workdir / name)
    owner.sweep(workdir, f".{what}.")
    stage = Path(os.path.abspath(staging_dir(workdir, f".{what}.{owner.tag()}.")))
    try:
        log = stage / outputs["log"] if "log" in outputs else None
        with open(log if log else os.devnull, "w") as f:
            p = children.run(args_of(stage), stdin=subprocess.DEVNULL, stdout=f, stderr=subprocess.STDOUT,
                             cwd=cwd or stage)
        moved = {}
        for src, name in outputs.items():
            file = stage / (name if src == "log" else src)
            if file.is_file() and not file.is_symlink():
                moved[src] = move_into(file, workdir / name)
            elif src != "log":
                Path(workdir / name).unlink(missing_ok=True)   # no stale result beside a new log
        return p.returncode, moved
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def drc_command(gds: Path, top: str, tech, workdir: Path, threads: int = 2, mode: str | None = None) -> tuple:
    """(KLayout's arguments, report path, log path, deck, options) of the technology's DRC deck on cell
    ``top`` of ``gds`` with its report and log in ``workdir``."""
    deck = drc_deck(tech)
    exe = klayout_binary()
    workdir = Path(workdir)
    report = workdir / f"{top}.lyrdb"
    log = workdir / f"{top}.drc.log"
    options = dict(tech.signoff.drc_options)
    if mode:
        options["run_mode"] = mode
    if not re.fullmatch(r"[A-Za-z0-9_]+", top):
        raise PixelkitError(f"cell name {top!r}: expected letters, digits and '_'")
    script = ["-r", str(deck)] if "%include" in deck.read_text(errors="replace") else \
        ["-r", str(RUNNER), "-rd", f"pixelkit_deck={deck}"]
    args = [exe, "-b", *script, "-rd", f"input={Path(gds).resolve()}", "-rd", f"report={report.resolve()}",
            "-rd", f"topcell={top}", "-rd", f"thr={threads}"]
    for k, v in sorted(options.items()):
        args += ["-rd", f"{k}={v}"]
    return args, report, log, deck, options


def drc_result(code: int, gds, top: str, report: Path, log: Path, deck: Path, options: dict, seconds: float) -> DrcResult:
    """The result of a finished DRC run (its exit status, report and log), or an error naming the log."""
    if code != 0 or not report.is_file():
        tail = log.read_text(errors="replace").strip().splitlines()[-3:]
        raise PixelkitError(f"the DRC deck {deck.name} failed on {gds} (exit {code}): "
                            f"{' | '.join(tail)}; log: {log}")
    return DrcResult(str(deck), top, options, seconds, klayout_version(), parse_report(report), str(report))


def run_drc(gds: Path, top: str, tech, workdir: Path, threads: int = 2, mode: str | None = None,
            cache: bool = False) -> DrcResult:
    """Run the technology's DRC deck on cell ``top`` of ``gds``; report and log in ``workdir``, written by
    KLayout in a private stage there and renamed into place (:func:`klayout_run`). ``cache``: take the
    result of an earlier run on the same bytes from the DRC cache, and keep this one there (module
    docstring)."""
    drc_deck(tech)   # verified (pinned) before anything is made
    if cache:
        key, deck = _cache_key(gds, top, tech, mode)
        hit = _from_cache(key, top, workdir, deck)
        if hit is not None:
            return hit
        result = run_drc(gds, top, tech, workdir, threads, mode)
        _to_cache(key, result, Path(workdir) / f"{top}.drc.log")
        return result
    meta = {}

    def args(stage: Path) -> list[str]:
        a, report, _log, deck, options = drc_command(gds, top, tech, stage, threads, mode)
        meta.update(deck=deck, options=options)
        return a

    t0 = time.perf_counter()
    code, files = klayout_run(args, workdir, {f"{top}.lyrdb": f"{top}.lyrdb", "log": f"{top}.drc.log"}, "drc")
    workdir = Path(workdir)
    report = files.get(f"{top}.lyrdb", workdir / f"{top}.lyrdb")
    return drc_result(code, gds, top, Path(report), workdir / f"{top}.drc.log", meta["deck"], meta["options"],
                      time.perf_counter() - t0)


_STORE = None
#: in a stored report, the runner's path (the report's generator line names the script that ran): a hit
#: in another checkout of the kit names its own runner, as a run there would
_HERE = b"\0pixelkit-deck-runner\0"


def _store():
    global _STORE
    if _STORE is None:
        from ...cachestore import Store
        _STORE = Store("drc", "report-cache", "running the deck again")
    return _STORE


def _cache_key(gds: Path, top: str, tech, mode: str | None) -> tuple[str, Path]:
    """(the key of everything the deck's verdict on ``top`` of ``gds`` depends on (module docstring),
    the deck)."""
    from .deckcache import sha256
    _args, _report, _log, deck, options = drc_command(gds, top, tech, Path("."), 2, mode)
    h = hashlib.sha256(b"pixelkit drc cache 1\0")
    for part in (sha256(Path(gds)), top, sha256(deck),
                 sha256(RUNNER) if "%include" not in deck.read_text(errors="replace") else "direct",
                 json.dumps(options, sort_keys=True), klayout_version()):
        h.update(str(part).encode() + b"\0")
    return h.hexdigest(), deck


def _from_cache(key: str, top: str, workdir: Path, deck: Path) -> DrcResult | None:
    """The stored run of ``key`` with its report and log written into ``workdir``, or None."""
    from ...fileio import check_target, out_folder, write_atomic
    files = _store().load(key)
    if files is None:
        return None
    try:
        meta = json.loads(files["result.json"])
        report_bytes, log_bytes = files["report.lyrdb"], files["drc.log"]
        meta["options"], meta["seconds"], meta["klayout"]  # noqa: B018 - all there, or the entry is not one
    except (KeyError, ValueError, TypeError):
        _store().drop(key)
        return None
    workdir = out_folder(workdir)
    report, log = workdir / f"{top}.lyrdb", workdir / f"{top}.drc.log"
    for p in (report, log):
        check_target(p)
    write_atomic(report, report_bytes.replace(_HERE, str(RUNNER).encode()))
    write_atomic(log, f"pixelkit: DRC result from the cache (entry {key[:16]}: the same GDS bytes, top cell, "
                      f"deck, options and KLayout); the log of the run that made it follows\n".encode() + log_bytes)
    return DrcResult(str(deck), top, meta["options"], float(meta["seconds"]), meta["klayout"],
                     parse_report(report), str(report), cached=True)


def _to_cache(key: str, result: DrcResult, log: Path) -> None:
    meta = {"options": result.options, "seconds": result.seconds, "klayout": result.klayout}
    report = Path(result.report).read_bytes().replace(str(RUNNER).encode(), _HERE)
    _store().save(key, {"result.json": json.dumps(meta).encode(), "report.lyrdb": report,
                        "drc.log": log.read_bytes() if log.is_file() else b""})
