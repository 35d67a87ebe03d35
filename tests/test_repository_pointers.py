"""Nothing in the repository points at a document a user of the kit does not have.

A clone is all a user has: no README line, docstring, comment, design file or test may send
the reader to the development machine's background folder or its notes (the team's design,
effects, simulator and sign-off notes, the English brief of the source documents, the
numbered source files), and every citation key is defined in ``docs/bibliography.md``.
Independent check: a plain text scan of every file of the clone (not the code's own idea of
what it reads); the scanner is shown to catch a planted pointer and an uncited mention.
"""
from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Folders that are not the kit's own text: vendor model files, data, generated output.
SKIP_DIRS = {".git", ".venv", "venv", "reports", "__pycache__", ".pytest_cache", "build", "dist", "site"}
SKIP_UNDER = ("tests/data/", "pixelkit/tech/models/")
TEXT_SUFFIXES = {".py", ".md", ".toml", ".txt", ".sh", ".j2", ".html", ".css", ".cfg", ".ini", ".yml",
                 ".yaml", ".cir", ".spice", ".json", ".csv", ""}

# Built from pieces so that this file does not match itself.
_NOTES = "|".join(n + "_NOTES" for n in ("NGSPICE", "SIGNOFF")) + "|SEEDS" + "_BRIEF"
POINTERS = [
    ("the background folder", re.compile(r"\.\./" + "shared|/work/" + r"(?:shared|wt|main)\b")),
    ("the team's notes", re.compile(r"\b(?:" + _NOTES + r")\b")),
    ("the team's design or effects notes", re.compile(r"\b(?:DESIGN|EFFECTS)\.md\b|\bEFFECTS\.md|\bEFFECTS (?:row|table|section)\b")),
    ("a numbered source file", re.compile(r"\b(?i:sources?|documents?) 00\d\b|\b00[1-4](?:'s\b| eq\.)|\b00\d_\w+_(?:hu|ru|zh)\.txt\b|\bseeds/")),
]
#: "the thesis" as a word (not the module experiments.thesis, the technology c35_thesis, a THESIS table)
THESIS = re.compile(r"(?<![\w./])[Tt]hesis(?!\w|\.[a-z_])")
#: author-year citation keys, e.g. [Thesis2019], [Rychazhnikov2008a]
CITE = re.compile(r"\[([A-Z][A-Za-z]*(?:19|20)\d\d[a-z]?)\]")
BIB = ROOT / "docs" / "bibliography.md"


def _files(root: Path):
    for p in sorted(root.rglob("*")):
        rel = p.relative_to(root).as_posix()
        if not p.is_file() or set(p.relative_to(root).parts[:-1]) & SKIP_DIRS or rel.startswith(SKIP_UNDER):
            continue
        if p.suffix not in TEXT_SUFFIXES or p.name == ".git":  # a worktree's .git file names its gitdir
            continue
        try:
            yield rel, p.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue


def defined_keys(bib_text: str) -> set[str]:
    return set(re.findall(r"^#{2,4} \[([^\]]+)\]", bib_text, flags=re.M))


def scan(root: Path, keys: set[str], skip: tuple = ()) -> list[str]:
    """Every offence in the tree under ``root``: 'file:line: what'."""
    bad = []
    for rel, text in _files(root):
        if rel in skip:
            continue
        for n, line in enumerate(text.splitlines(), 1):
            for what, rx in POINTERS:
                if rx.search(line):
                    bad.append(f"{rel}:{n}: points at {what}: {line.strip()[:120]}")
            for key in CITE.findall(line):
                if key not in keys:
                    bad.append(f"{rel}:{n}: citation key [{key}] is not in docs/bibliography.md")
        if THESIS.search(text) and "[Thesis2019]" not in text:
            n = next(i for i, line in enumerate(text.splitlines(), 1) if THESIS.search(line))
            bad.append(f"{rel}:{n}: mentions the thesis without its citation key [Thesis2019]")
    return bad


def test_no_file_points_outside_the_repository():
    keys = defined_keys(BIB.read_text(encoding="utf-8"))
    bad = scan(ROOT, keys, skip=("tests/test_repository_pointers.py",))
    assert not bad, "\n".join(bad)


def test_bibliography_defines_the_source_documents_and_tools():
    keys = defined_keys(BIB.read_text(encoding="utf-8"))
    assert {"Thesis2019", "Rychazhnikov2008a", "Rychazhnikov2008b", "Zhou2017", "Sun2016", "EMVA1288",
            "GF180MCU", "ngspice", "KLayout", "casadi"} <= keys


def test_the_scan_catches_a_planted_pointer_and_an_uncited_thesis(tmp_path):
    """The check can fail: each kind of offence in a planted tree is reported."""
    planted = {
        "a.py": '"""See ../' + 'shared/DESIGN.md for why."""\n',
        "b.md": "As EFFECTS" + ".md row 3 says.\n",
        "c.toml": "# (source " + "002)\nname = 'x'\n",
        "g.py": "# the published forms of document" + "s 001/003\n",
        "h.py": "# 00" + "3's L_up is too long\n",
        "d.py": "# the thesis's table 3.2\n",
        "e.md": "as [Nobody1999] showed\n",
        "f.py": "# NGSPICE" + "_NOTES: one thread\n",
        "ok.py": "from .experiments.thesis import run  # c35_thesis, THESIS = {}\n# the thesis [Thesis2019]\n",
    }
    for name, text in planted.items():
        (tmp_path / name).write_text(text)
    bad = scan(tmp_path, {"Thesis2019"})
    files = sorted({b.split(":")[0] for b in bad})
    assert files == ["a.py", "b.md", "c.toml", "d.py", "e.md", "f.py", "g.py", "h.py"], bad
