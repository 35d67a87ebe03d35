"""Record every deck a pixelkit command hands to ngspice, for ``benchmarks/main_job.py``.

    python benchmarks/deck_log.py FOLDER pixelkit-arguments ...

runs ``python -m pixelkit pixelkit-arguments ...`` with the batch runner
(``pixelkit.spice.engine.run_batch``, present in every version the benchmark compares) wrapped:
each deck that really runs (not one served from the cache) is written to ``FOLDER/decks/`` as
ngspice read it, with the folders its links name (model files; the run's flattened library
sections, copied, since the run's scratch folder goes when it ends), and one JSON line in
``FOLDER/decks.jsonl``: title, transient stop time, the run's wall time, the deck's file and its
links. The replay (``main_job.replay``) runs the same files with raw ``ngspice -b``.
Nothing of pixelkit is changed: the wrapper only reads what it hands over.
"""
from __future__ import annotations

import json
import os
import re
import runpy
import shutil
import sys
import threading
import time
from pathlib import Path

_LOCK = threading.Lock()
_COPIED: dict = {}
_TRAN = re.compile(r"^\.tran\s+(\S+)\s+(\S+)", re.I | re.M)
_SCALE = {"f": 1e-15, "p": 1e-12, "n": 1e-9, "u": 1e-6, "m": 1e-3, "k": 1e3}


def _seconds(token: str) -> float | None:
    m = re.match(r"^([0-9.eE+-]+)([a-zA-Z]*)$", token)
    if not m:
        return None
    try:
        return float(m.group(1)) * _SCALE.get(m.group(2)[:1].lower(), 1.0)
    except ValueError:
        return None


def _keep_links(folder: Path, links: dict) -> dict:
    """Each link target as the replay will find it: a scratch folder (under the temp root) copied
    once into ``folder/links``; anything else (the model folders of the tree) by its path."""
    out = {}
    tmp = os.path.realpath(os.environ.get("TMPDIR", "/tmp"))
    for name, target in (links or {}).items():
        target = os.path.realpath(str(target))
        if target.startswith(tmp + os.sep) and Path(target).is_dir():
            with _LOCK:
                dest = _COPIED.setdefault(target, folder / "links" / f"{name}-{len(_COPIED)}")
                dest.mkdir(parents=True, exist_ok=True)
                for f in Path(target).iterdir():   # new files since the last deck (a section per corner)
                    if f.is_file() and not (dest / f.name).exists():
                        shutil.copy2(f, dest / f.name)
                target = str(dest)
        out[name] = target
    return out


def install(folder: Path) -> None:
    from pixelkit.spice import engine
    (folder / "decks").mkdir(parents=True, exist_ok=True)
    log = open(folder / "decks.jsonl", "a", buffering=1)
    count = [0]
    original = engine.run_batch

    def run_batch(deck_text, links=None, timeout=600.0):
        t0 = time.perf_counter()
        out = original(deck_text, links, timeout)
        wall = time.perf_counter() - t0
        with _LOCK:
            count[0] += 1
            name = f"decks/{count[0]:06d}.cir"
        (folder / name).write_text(deck_text)
        tran = _TRAN.search(deck_text)
        rec = {"title": deck_text.split("\n", 1)[0].lstrip("* ").split(":")[0], "file": name, "wall_s": wall,
               "tran_stop_s": _seconds(tran.group(2)) if tran else None, "ok": bool(out[0]),
               "links": _keep_links(folder, links)}
        with _LOCK:
            log.write(json.dumps(rec) + "\n")
        return out

    engine.run_batch = run_batch


def main() -> None:
    if sys.path and Path(sys.path[0]).resolve() == Path(__file__).resolve().parent:
        sys.path.pop(0)   # the benchmark scripts' names (gap, report, verify) must not shadow anything
    folder = Path(sys.argv[1]).resolve()
    install(folder)
    sys.argv = ["pixelkit", *sys.argv[2:]]
    runpy.run_module("pixelkit", run_name="__main__", alter_sys=True)


if __name__ == "__main__":
    main()
