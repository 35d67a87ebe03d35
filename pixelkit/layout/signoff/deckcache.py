"""The deck cache (``$PIXELKIT_DECKS``) and its error, shared by the decks the kit fetches
(``decks.py``: the DRC deck from a wheel; ``fdpv.py``: the foundry's fd_pv decks from GitHub)."""
from __future__ import annotations

import hashlib
import os
from pathlib import Path

from ...errors import PixelkitError


class DeckError(PixelkitError):
    """A deck is missing, altered or cannot be fetched."""


def deck_dir() -> Path:
    env = os.environ.get("PIXELKIT_DECKS")
    if env:
        return Path(env)
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "pixelkit" / "decks"


def deck_label(path) -> str:
    """``path`` as an output names it: a deck in the decks' folder by that folder as the user sets it
    (``$PIXELKIT_DECKS/...``, ``$XDG_CACHE_HOME/pixelkit/decks/...`` or ``~/.cache/pixelkit/decks/...``),
    never by this machine's absolute path (a report or a sign-off record is sent to others)."""
    text, folder = str(path), str(deck_dir())
    if not text.startswith(folder + os.sep):
        return text
    if os.environ.get("PIXELKIT_DECKS"):
        name = "$PIXELKIT_DECKS"
    elif os.environ.get("XDG_CACHE_HOME"):
        name = "$XDG_CACHE_HOME/pixelkit/decks"
    else:
        name = "~/.cache/pixelkit/decks"
    return name + text[len(folder):]


def sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


