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


def sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


