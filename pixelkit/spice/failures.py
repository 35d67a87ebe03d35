"""Keeping a failed simulation: its deck and ngspice's log in a named folder, and advice.

The engine calls :func:`keep` when a deck still fails after every retry. The
folder is ``<root>/<deck title>-<hash>/`` with ``deck.cir`` (the deck as last
run, options included, so ``ngspice -b deck.cir`` reproduces the failure),
``ngspice.log`` (ngspice's output of every attempt), a ``models`` link to the
model folder and ``what.txt`` (which
bench and operating point, in the user's terms). ``root`` is
``reports/<design>/failed`` for the command line (``set_root``), else (the
Python API, tests) ``failed/`` in the kit's cache folder (``$PIXELKIT_CACHE``,
default ``~/.cache/pixelkit``): library code does not write into the current
folder on its own.
"""
from __future__ import annotations

import hashlib
from pathlib import Path

from ..fileio import write_atomic

_ROOT: Path | None = None


def set_root(folder) -> None:
    global _ROOT
    _ROOT = Path(folder)


def root() -> Path:
    if _ROOT is not None:
        return _ROOT
    from .cache import cache_dir
    return cache_dir().parent / "failed"


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
    folder = root() / f"{net.title}-{tag}"
    export_deck(net, folder / "deck.cir", models="link")
    log = []
    for label, lines in logs:
        log += [f"==== {label}", *lines, ""]
    write_atomic(folder / "ngspice.log", "\n".join(log) + "\n")
    write_atomic(folder / "what.txt", describe(net) + "\n")
    return folder
