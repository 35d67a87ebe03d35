"""Decks that run as they are in ``ngspice -b``, outside the kit.

The kit's engine adds its simulator options (``options.DEFAULTS``) at run time
and names model files through a link (``models/<file>``) it makes in each run's
scratch folder. An exported deck carries both itself:

- the ``.options`` line the engine would use (without it the bench signals
  come out 14 - 18 % smaller: the default ``gmin`` drains the fF nodes);
- the model includes, either resolved to absolute paths (``models="absolute"``,
  the default: the deck runs from anywhere on this machine) or kept as
  ``models/<file>`` with a ``models`` link written beside the deck
  (``models="link"``: one documented line per file; the link is the only
  machine-specific part, re-point it with ``ln -sfn <folder> models``);
- the stimulus and the analysis, as the engine runs them, and a ``.print``
  line of the bench's outputs: ``ngspice -b deck.cir`` prints them (without a
  ``.print`` ngspice -b simulates nothing); ``ngspice -b -r out.raw deck.cir``
  writes every vector to a raw file (the ``.print`` is then silent).

ngspice resolves a relative include against the folder of the deck, so a
``link`` deck runs from any working directory. The golden netlists
(``netlists/*.cir``) are written in ``link`` form next to a committed relative
link ``netlists/models`` to the model files shipped in the package.
"""
from __future__ import annotations

import os
import re
from pathlib import Path

from ..errors import ConfigError
from ..fileio import write_atomic
from .options import DEFAULTS, merged

_PATH_OK = re.compile(r"^[\x20-\x7e]+$")
MODES = ("absolute", "link")


def _links(net) -> dict:
    return net.model_links() if hasattr(net, "model_links") else {}


def deck_text(net, models: str = "link") -> str:
    """The deck text with the kit's options; model lines resolved (``absolute``) or by link."""
    if models not in MODES:
        raise ConfigError("", "models", models, f"one of {', '.join(MODES)}")
    from dataclasses import replace
    net = replace(net, options=merged(DEFAULTS, net.options))
    text = _with_print(net, net.text())
    if models == "absolute":
        for link, folder in _links(net).items():
            folder = str(Path(folder).resolve())
            if not _PATH_OK.match(folder) or any(c in folder for c in '";'):
                raise ConfigError("", "models folder", folder,
                                  "a path of printable characters without quotes or ';' "
                                  "(or export with models='link')")
            text = text.replace(f'"{link}/', f'"{folder}/')
    return text


_OUTPUT_PREFIXES = ("col", "out", "pd")


def outputs(net) -> list[str]:
    """The bench's output nodes (columns, AFE outputs, bare PDs) for the ``.print`` line."""
    nodes = dict.fromkeys(n for e in net.elements for n in e.nodes)
    for prefix in _OUTPUT_PREFIXES:
        found = [n for n in nodes if n.lower().startswith(prefix)]
        if found:
            return found[:12]
    return []


def _with_print(net, text: str) -> str:
    """Add ``.print tran v(...)`` of the outputs, so a plain ``ngspice -b deck`` prints them."""
    nodes = outputs(net)
    if getattr(net.analysis, "kind", "") != "tran" or not nodes:
        return text
    line = ".print tran " + " ".join(f"v({n})" for n in nodes)
    tran = net.analysis.text()
    return text.replace(f"\n{tran}\n", f"\n{line}\n{tran}\n", 1)


def export_deck(net, path: Path, models: str = "absolute", design=None) -> Path:
    """Write ``net`` to ``path`` as a self-contained ngspice deck; ``link`` also writes the links."""
    path = Path(path)
    if path.suffix.lower() not in (".cir", ".sp", ".spice", ".net"):
        raise ConfigError("", "--out", str(path), "a deck file name ending in .cir, .sp, .spice or .net")
    text = deck_text(net, models)
    head = (f"* run with: ngspice -b {path.name}  (prints the outputs) or ngspice -b -r out.raw {path.name}"
            "  (every vector); pixelkit export: options and models as the kit runs them\n")
    write_atomic(path, head + text)
    if models == "link":
        for link, folder in _links(net).items():
            make_link(path.parent / link, Path(folder))
    return path


def make_link(link: Path, folder: Path) -> None:
    """``link`` -> ``folder`` (relative inside one tree, e.g. the repository), replaced atomically."""
    src, dst = link.parent.resolve(), folder.resolve()
    try:
        common = os.path.commonpath([src, dst])
    except ValueError:  # another drive
        common = os.sep
    target = os.path.relpath(dst, src) if common != os.sep else str(dst)
    if link.is_symlink() and os.readlink(link) == target:
        return
    tmp = link.with_name(f".{link.name}.tmp{os.getpid()}")
    if tmp.is_symlink():
        tmp.unlink()
    os.symlink(target, tmp, target_is_directory=True)
    os.replace(tmp, link)
