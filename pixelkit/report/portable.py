"""No absolute path of the user's machine in a report: a report is sent to others, diffed against
the next revision's and kept for years, so the places it names are relative to the report
(``layout_signoff/lvs/CHIP.lvsdb``), to the kit's cache (``$PIXELKIT_CACHE/decks/...``) or to the
home folder (``~/...``), to the folder the command ran in (``designs/x.toml``) or to the kit
(``pixelkit/layout/signoff/deck_runner.drc``). Applied to every section's text, tables, figures,
checked notes and data, and to the text files it wrote (KLayout's report databases among them),
before anything is written (``build.build_report``), cached sections included.
"""
from __future__ import annotations

from pathlib import Path


def _roots(stage: Path) -> list[tuple[str, str]]:
    from ..cachestore import cache_root
    roots = [(str(Path(stage).resolve()), "."), (str(Path(stage)), "."), (str(cache_root()), "$PIXELKIT_CACHE"),
             (str(Path.home()), "~"), (str(Path.cwd()), "."),   # the design named from where the command ran
             (str(Path(__file__).resolve().parents[1]), "pixelkit")]   # the kit's own files (a deck's runner)
    import os
    if os.environ.get("PIXELKIT_DECKS"):   # the foundry decks' folder (layout.signoff.decks)
        roots.append((str(Path(os.environ["PIXELKIT_DECKS"])), "$PIXELKIT_DECKS"))
    # the longest first: the stage or the cache may lie under the home folder
    return sorted({r for r in roots if r[0] not in ("", "/", ".")}, key=lambda r: -len(r[0]))


def portable(x, roots):
    """``x`` (str, list, tuple or dict, nested) with every path under one of ``roots`` rewritten."""
    if isinstance(x, str):
        for root, name in roots:
            if root in x:
                x = x.replace(root + "/", "" if name == "." else name + "/").replace(root, name)
        return x
    if isinstance(x, dict):
        return {k: portable(v, roots) for k, v in x.items()}
    if isinstance(x, list):
        return [portable(v, roots) for v in x]
    if isinstance(x, tuple):
        return tuple(portable(v, roots) for v in x)
    return x


#: files a section writes beside the HTML whose text is rewritten too (the sized design's header,
#: KLayout's DRC / LVS databases, which name the deck that wrote them)
TEXT_FILES = (".toml", ".cir", ".csv", ".json", ".txt", ".log", ".lyrdb", ".lvsdb")


def portable_section(s, stage: Path) -> None:
    """Rewrite the paths of section ``s`` (in place), and those in the text files it wrote."""
    roots = _roots(stage)
    for name in s.files:
        f = Path(stage) / name
        if f.suffix.lower() in TEXT_FILES and f.is_file() and not f.is_symlink():
            text = f.read_text(errors="surrogateescape")
            new = portable(text, roots)
            if new != text:
                f.write_text(new, errors="surrogateescape")
    s.text = portable(s.text, roots)
    s.why = portable(s.why, roots)
    s.flags = portable(s.flags, roots)
    s.data = portable(s.data, roots)
    for t in s.tables:
        t.caption, t.rows = portable(t.caption, roots), portable(t.rows, roots)
    for f in s.figures:
        f.caption = portable(f.caption, roots)
    for c in s.checked:
        c.note = portable(c.note, roots)
