"""Keeping a failed simulation: its deck and ngspice's log in a folder of its own, and advice.

The engine calls :func:`keep` when a deck still fails after every retry. The
folder is ``$PIXELKIT_CACHE/failed/<deck title>-<deck hash>-<time>-<random>/``
(default cache ``~/.cache/pixelkit``; never the current folder), one per failure,
so two failures of the same deck (with different model folders, say) never
overwrite each other; its path is in the error message. It holds ``deck.cir`` (the
deck as last run, options included, so ``ngspice -b deck.cir`` reproduces the
failure), ``ngspice.log`` (ngspice's output of every attempt), a ``models`` link to
the model folder and ``what.txt`` (which bench and operating point, in the user's
terms). The newest ``KEEP`` folders are kept; older ones are removed.
"""
from __future__ import annotations

import hashlib
import shutil
import time
from pathlib import Path

from ..cachestore import cache_root
from ..fileio import staging_dir, write_atomic

KEEP = 100


def root() -> Path:
    return cache_root() / "failed"


def describe(net) -> str:
    """The bench and operating point of ``net`` in the user's terms (``meta['what']``), or its title."""
    return net.meta.get("what") or f"deck '{net.title}'"


def hints(message: str) -> list[str]:
    """What the user can change, from ngspice's message."""
    low = message.lower()
    out = []
    if "timestep too small" in low or "no convergence" in low or "gmin" in low or "singular" in low:
        out += ["check that the reset levels (pixel.v_pd_reset, pixel.v_fd_reset) leave the switches a hard "
                "reset (below the gate level minus the NMOS threshold; see the working-range warning)",
                "check the photocurrent / exposure: a PD driven far below 0 V forward-biases its junction",
                "try --backend shared (another ngspice build) or run the kept deck.cir in ngspice to inspect"]
    elif "could not find" in low or "can't find" in low or "unknown" in low:
        out += ["check the technology's [models] folder and corner (pixelkit models DESIGN lists them)"]
    else:
        out += ["run the kept deck.cir with `ngspice -b deck.cir` and read ngspice.log"]
    return out


def keep(net, deck_text: str, logs: list[tuple[str, list[str]]]) -> Path:
    """Write the failed deck (runnable there: ``models`` link beside it), the logs and the description."""
    from .export import export_deck
    tag = hashlib.sha256(deck_text.encode()).hexdigest()[:8]
    root().mkdir(parents=True, exist_ok=True)
    folder = staging_dir(root(), f"{net.title}-{tag}-{time.strftime('%Y%m%d-%H%M%S')}-")
    _prune()
    export_deck(net, folder / "deck.cir", models="link")
    log = []
    for label, lines in logs:
        log += [f"==== {label}", *lines, ""]
    write_atomic(folder / "ngspice.log", "\n".join(log) + "\n")
    write_atomic(folder / "what.txt", describe(net) + "\n")
    return folder


def _prune() -> None:
    """Keep the newest KEEP failure folders."""
    try:
        folders = sorted((p for p in root().iterdir() if p.is_dir() and not p.is_symlink()),
                         key=lambda p: p.stat().st_mtime)
    except OSError:
        return
    for p in folders[:-KEEP]:
        shutil.rmtree(p, ignore_errors=True)
