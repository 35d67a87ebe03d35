"""The foundry's own physical-verification decks in the flow (``fdpv.py`` fetches and pins them):
LVS in deep mode on the hierarchy with every label kept, and the chip-level density and antenna
DRC decks.

A technology names them in ``[signoff]``: ``pv_decks = "gf180mcu_fd_pv"``, the LVS switches in
``pv_options`` (``lvs_sub`` the substrate's net, ``metal_top`` ...) and, where the kit's netlists name
a device by another name than the foundry's extraction does (a stand-in junction), ``lvs_models``
({kit's name: foundry's name}, applied to the netlist handed to the deck).

Every deck runs in a private temporary folder (its report, log and extracted netlist are moved
into the output folder afterwards, each renamed into place: nothing is written through a link
someone placed there), through the kit's runners (``deck_runner.lvs`` / ``.drc``: the decks'
text unchanged, their includes resolved and their per-message ``pmap`` answered from /proc).
The verdict is read from the deck's report (the LVS database's cross reference; the DRC marker
database), never from its log.
"""
from __future__ import annotations

import re
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from ... import children
from ...errors import PixelkitError
from . import fdpv
from .deckcache import DeckError

LVS_RUNNER = Path(__file__).with_name("deck_runner.lvs")
DRC_RUNNER = Path(__file__).with_name("deck_runner.drc")
KNOWN = {fdpv.NAME: fdpv}


@dataclass
class NotRun:
    """A check that was asked but could not run (the deck is not installed): exit 5."""
    check: str
    reason: str

    def as_dict(self) -> dict:
        return {"run": False, "check": self.check, "reason": self.reason}


def pv_module(tech):
    """The deck set the technology names (``[signoff] pv_decks``), or None."""
    name = tech.signoff.pv_decks
    if not name:
        return None
    if name not in KNOWN:   # parse_signoff refuses other names; kept as a guard
        raise PixelkitError(f"[signoff] pv_decks = {name!r}: expected one of {', '.join(KNOWN)}")
    return KNOWN[name]


def available(tech) -> str | None:
    """None when the technology's foundry decks can run here; else why not (one line)."""
    mod = pv_module(tech)
    if mod is None:
        return f"technology {tech.name} names no foundry LVS / density / antenna decks ([signoff] pv_decks)"
    return mod.check()


class Job:
    """A KLayout batch run in a private temporary folder of its own, started now; ``result()`` waits for
    it and hands (exit status, log text, folder) to ``finish``, whose return it gives back (the folder is
    removed after). Lets the sign-off run its decks side by side with its own work."""

    def __init__(self, args: list, finish, prefix: str = "pixelkit-deck-", folder: Path | None = None):
        from .drc import klayout_binary
        self._tmp = None
        if folder is None:
            self._tmp = tempfile.TemporaryDirectory(prefix=prefix)
            folder = Path(self._tmp.name)
        self.folder = Path(folder)
        self.finish = finish
        self.t0 = time.perf_counter()
        args = args(self.folder) if callable(args) else args
        self._log = open(self.folder / "run.log", "w")
        self.proc = children.popen([klayout_binary(), "-b", *args], stdin=subprocess.DEVNULL,   # dies with the kit
                                   stdout=self._log, stderr=subprocess.STDOUT, cwd=self.folder)
        self.t_end = None
        import threading
        self._waiter = threading.Thread(target=self._wait, daemon=True, name="pixelkit-wait-deck")  # pex.beside.WAITERS
        self._waiter.start()

    def _wait(self):
        self.proc.wait()
        self.t_end = time.perf_counter()
        children.forget(self.proc)

    def result(self):
        try:
            code = self.proc.wait()
            self._waiter.join()
            self._log.close()
            return self.finish(code, (self.folder / "run.log").read_text(errors="replace"), self.folder)
        finally:
            if self.proc.poll() is None:
                self.proc.kill()
            if self._tmp is not None:
                self._tmp.cleanup()

    def seconds(self) -> float:
        """Wall time of the run (from its start to its end)."""
        return (self.t_end or time.perf_counter()) - self.t0


def _move_out(tmp: Path, names: dict, workdir: Path) -> dict:
    """Move the deck's files ({name in tmp: name in workdir}) into ``workdir``, each renamed into place."""
    from ...fileio import write_atomic
    out = {}
    for src, dst in names.items():
        f = tmp / src
        if f.is_file():
            out[dst] = str(write_atomic(Path(workdir) / dst, f.read_bytes()))
    return out


def renamed_netlist(spice_text: str, models: tuple) -> str:
    """``spice_text`` with each device model of ``models`` ((kit's, foundry's), ...) renamed on its cards."""
    for old, new in models:
        spice_text = re.sub(rf"(?im)^([DMXCR]\S*\s.*?\s){re.escape(old)}(\s|$)", rf"\g<1>{new}\g<2>", spice_text)
    return spice_text


@dataclass
class FoundryLvs:
    top: str
    match: bool
    seconds: float
    deck: str
    circuits: dict = field(default_factory=dict)    # circuit -> status (Match, NoMatch, Skipped ...)
    mismatches: list = field(default_factory=list)
    report: str = ""
    log: str = ""

    def as_dict(self) -> dict:
        return {"run": True, "match": self.match, "top": self.top, "seconds": round(self.seconds, 2),
                "deck": self.deck, "circuits": self.circuits, "mismatches": self.mismatches,
                "report": self.report, "log": self.log}


def run_lvs(gds: Path, top: str, spice: Path, tech, workdir: Path) -> FoundryLvs | NotRun:
    """The foundry's LVS deck, deep mode, on cell ``top`` of ``gds`` against the netlist ``spice``."""
    job = start_lvs(gds, top, Path(spice).read_text(), tech, workdir)
    return job if isinstance(job, NotRun) else job.result()


def start_lvs(gds: Path, top: str, spice_text: str, tech, workdir: Path):
    """Start the foundry's LVS deck (a :class:`Job` whose result is a :class:`FoundryLvs`), or
    :class:`NotRun` where the deck is not installed."""
    mod = pv_module(tech)
    why = available(tech)
    if why is not None:
        return NotRun("foundry LVS", why)
    deck = mod.deck(mod.LVS_DECK)
    so = tech.signoff

    def args(tmp):
        (tmp / "schematic.spice").write_text(renamed_netlist(spice_text, so.lvs_models))
        out = ["-r", str(LVS_RUNNER), "-rd", f"pixelkit_deck={deck}", "-rd", f"input={Path(gds).resolve()}",
               "-rd", f"schematic={tmp / 'schematic.spice'}", "-rd", f"report={tmp / 'out.lvsdb'}",
               "-rd", f"target_netlist={tmp / 'out.cir'}", "-rd", f"topcell={top}", "-rd", "run_mode=deep"]
        for k, v in so.pv_options:
            out += ["-rd", f"{k}={v}"]
        return out

    def finish(code, log, tmp):
        import klayout.db as kdb
        from .lvs import _describe
        if not (tmp / "out.lvsdb").is_file():
            tail = " | ".join(log.strip().splitlines()[-2:])
            raise PixelkitError(f"the foundry LVS deck ({mod.SOURCE}) wrote no report on {gds} (exit {code}): {tail}")
        db = kdb.LayoutVsSchematic()
        db.read(str(tmp / "out.lvsdb"))
        xref = db.xref()
        circuits = {}
        for cp in xref.each_circuit_pair():
            a, b = cp.first(), cp.second()
            circuits[(a or b).name] = str(cp.status()).split(".")[-1]
        # every circuit of the hierarchy must match: a parent can match with its children as black boxes
        good = (kdb.NetlistCrossReference.Match, kdb.NetlistCrossReference.MatchWithWarning)
        ok = bool(circuits) and all(cp.status() in good for cp in xref.each_circuit_pair())
        mismatches = [] if ok else (_describe(xref) or ["the netlists differ (see the report)"])
        files = _move_out(tmp, {"out.lvsdb": f"{top}.fdpv.lvsdb", "out.cir": f"{top}.fdpv.ext.cir",
                                "run.log": f"{top}.fdpv.lvs.log"}, workdir)
        said = "Netlists match" if "Netlists match" in log else "Netlists don't match" if "don't match" in log else "?"
        if said == "Netlists match" and not ok or said == "Netlists don't match" and ok:
            raise PixelkitError(f"the foundry LVS log says {said!r} but its report's cross reference says "
                                f"{'match' if ok else 'no match'} for {top}: not trusted; log "
                                f"{files.get(f'{top}.fdpv.lvs.log')}")
        return FoundryLvs(top, ok, job.seconds(), f"{mod.SOURCE}, patched: " + ", ".join(p.name for p in mod.patches()),
                          circuits, mismatches, files.get(f"{top}.fdpv.lvsdb", ""), files.get(f"{top}.fdpv.lvs.log", ""))
    job = Job(args, finish, "pixelkit-lvs-")
    return job


def run_chip_drc(gds: Path, top: str, tech, workdir: Path, which: str) -> object:
    """The foundry's ``density`` or ``antenna`` DRC deck on cell ``top`` (a chip-level check); a
    ``drc.DrcResult``, or :class:`NotRun`."""
    job = start_chip_drc(gds, top, tech, workdir, which)
    return job if isinstance(job, NotRun) else job.result()


def start_chip_drc(gds: Path, top: str, tech, workdir: Path, which: str):
    """Start the foundry's ``density`` or ``antenna`` deck (a :class:`Job` whose result is a
    ``drc.DrcResult``), or :class:`NotRun`."""
    from .drc import DrcResult, klayout_version, parse_report
    mod = pv_module(tech)
    why = available(tech)
    if why is not None:
        return NotRun(which, why)
    deck = mod.deck({"density": mod.DENSITY_DECK, "antenna": mod.ANTENNA_DECK}[which])
    options = {k: v for k, v in tech.signoff.drc_options if k in ("metal_top", "metal_level", "mim_option")}

    def args(tmp):
        out = ["-r", str(DRC_RUNNER), "-rd", f"pixelkit_deck={deck}", "-rd", f"input={Path(gds).resolve()}",
               "-rd", f"report={tmp / 'out.lyrdb'}", "-rd", f"topcell={top}", "-rd", "run_mode=deep", "-rd", "thr=2"]
        for k, v in sorted(options.items()):
            out += ["-rd", f"{k}={v}"]
        return out

    def finish(code, log, tmp):
        if code != 0 or not (tmp / "out.lyrdb").is_file():
            tail = " | ".join(log.strip().splitlines()[-2:])
            raise PixelkitError(f"the foundry {which} deck failed on {gds} (exit {code}): {tail}")
        violations = parse_report(tmp / "out.lyrdb")
        files = _move_out(tmp, {"out.lyrdb": f"{top}.{which}.lyrdb", "run.log": f"{top}.{which}.log"}, workdir)
        return DrcResult(str(deck), top, {**options, "run_mode": "deep"}, job.seconds(), klayout_version(),
                         violations, files.get(f"{top}.{which}.lyrdb", ""))
    job = Job(args, finish, f"pixelkit-{which}-")
    return job


__all__ = ["DeckError", "NotRun", "FoundryLvs", "available", "run_lvs", "run_chip_drc", "renamed_netlist"]
