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
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

from ...errors import PixelkitError
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
        return {"clean": self.clean, "total": self.total, "by_rule": self.by_rule(), "deck": self.deck,
                "top": self.top, "options": self.options, "seconds": round(self.seconds, 2),
                "klayout": self.klayout, "report": self.report,
                "violations": [v.__dict__ for v in self.violations]}


def klayout_binary() -> str:
    exe = shutil.which("klayout")
    if exe is None:
        raise PixelkitError(f"KLayout is not installed (no `klayout` on PATH): {KLAYOUT_HINT}")
    return exe


def klayout_version() -> str:
    from ... import children
    p = children.run([klayout_binary(), "-b", "-v"], capture_output=True, text=True, timeout=60)
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


def run_drc(gds: Path, top: str, tech, workdir: Path, threads: int = 2, mode: str | None = None) -> DrcResult:
    """Run the technology's DRC deck on cell ``top`` of ``gds``; report and log in ``workdir``, written by
    KLayout in a private stage there and renamed into place (:func:`klayout_run`)."""
    drc_deck(tech)   # verified (pinned) before anything is made
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
