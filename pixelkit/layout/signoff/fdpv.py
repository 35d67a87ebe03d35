"""GlobalFoundries' own GF180MCU physical-verification decks (fd_pv): the LVS deck, and the density
and antenna DRC decks the kit's DRC deck leaves out. Fetched, pinned, patched, never shipped.

No package registry carries them: they live in the repository
``fossi-foundation/globalfoundries-pdk-libs-gf180mcu_fd_pv`` (Apache-2.0). The kit pins one commit
(:data:`COMMIT`) and the sha256 of every file it runs (``fd_pv/files.sha256``, in ``sha256sum``
format), and installs them into the deck cache (``$PIXELKIT_DECKS``, ``decks.deck_dir()``) from

- GitHub, at that commit (``setup.sh``: ``python -m pixelkit.layout.signoff.decks --fetch``), where
  the machine reaches it; where it does not, set-up says so and goes on (the kit's own LVS needs no
  deck), or
- a checkout or unpacked archive of that repository the user already has
  (``python -m pixelkit.layout.signoff.decks --fd-pv-from DIR``, or ``$PIXELKIT_FD_PV=DIR``, which
  the kit installs from on first use).

Either way every file is checked against its pinned sha256 before anything is written; a file
that differs is refused, naming it. The known defects of the deck are then fixed by the patches in
``fd_pv/*.toml`` (each with its reason): a patch applies only to the pinned file it names, each
of its changes must match the text exactly once, and the patched file must have the sha256 the
patch pins. The installed copy is checked again, file by file, before every run: a deck whose
checksum differs is never run.
"""
from __future__ import annotations

import hashlib
import io
import os
import shutil
import tarfile
import tempfile
import tomllib
from dataclasses import dataclass
from pathlib import Path

from .deckcache import DeckError, deck_dir

REPOSITORY = "fossi-foundation/globalfoundries-pdk-libs-gf180mcu_fd_pv"
COMMIT = "50cc2fe338c81925e24a6ac4907ddaab534c1312"
NAME = "gf180mcu_fd_pv"
ARCHIVE_URL = f"https://codeload.github.com/{REPOSITORY}/tar.gz/{COMMIT}"
LVS_DECK = "klayout/lvs/gf180mcu.lvs"
DENSITY_DECK = "klayout/drc/rule_decks/density.drc"
ANTENNA_DECK = "klayout/drc/rule_decks/antenna.drc"
HERE = Path(__file__).with_name("fd_pv")
SOURCE = f"GF180MCU fd_pv decks (GlobalFoundries, Apache-2.0), {REPOSITORY} at {COMMIT[:7]}"
FETCH_HINT = ("python3 -m pixelkit.layout.signoff.decks --fetch (needs github.com), or with a checkout of "
              f"{REPOSITORY} at {COMMIT[:7]}: python3 -m pixelkit.layout.signoff.decks --fd-pv-from DIR "
              "(or PIXELKIT_FD_PV=DIR)")
_MAX_ARCHIVE = 200 << 20      # the repository's tarball is ~30 MB; refuse anything far larger


def pinned() -> dict:
    """{path in the repository: sha256} of every file the kit runs, as fetched."""
    out = {}
    for line in (HERE / "files.sha256").read_text().splitlines():
        if line.strip():
            sha, path = line.split(None, 1)
            out[path.strip()] = sha
    return out


@dataclass(frozen=True)
class Patch:
    name: str
    file: str
    reason: str
    changes: tuple         # ((before, after), ...)
    sha256_after: str


def patches() -> list[Patch]:
    """The patches of ``fd_pv/*.toml``, in name order; the reason is the file's comment header."""
    out = []
    for p in sorted(HERE.glob("*.toml")):
        text = p.read_text()
        raw = tomllib.loads(text)
        reason = " ".join(line[1:].strip() for line in text.splitlines() if line.startswith("#"))
        out.append(Patch(p.stem, raw["file"], reason, tuple((c["before"], c["after"]) for c in raw["change"]),
                         raw["sha256_after"]))
    return out


def patched(path: str, data: bytes, patch: Patch) -> bytes:
    """``data`` (the pinned file ``path``) with ``patch`` applied, every change checked first."""
    text = data.decode()
    for before, after in patch.changes:
        n = text.count(before)
        if n != 1:
            raise DeckError(f"patch {patch.name} of {path}: its text {before.strip()!r} occurs {n} times in the "
                            "pinned file (expected once): the patch does not fit this deck; nothing installed")
        text = text.replace(before, after)
    out = text.encode()
    got = hashlib.sha256(out).hexdigest()
    if got != patch.sha256_after:
        raise DeckError(f"patch {patch.name} of {path} gives sha256 {got}, not the pinned {patch.sha256_after}; "
                        "nothing installed")
    return out


def expected() -> dict:
    """{path: sha256} of the installed (patched) copy: the pinned files, patched ones by their patch."""
    out = pinned()
    for p in patches():
        out[p.file] = p.sha256_after
    return out


def install_dir() -> Path:
    return deck_dir() / f"{NAME}-{COMMIT[:12]}"


def _verified(files: dict) -> dict:
    """``files`` ({path: bytes}, as fetched) checked against the pins and patched."""
    pins = pinned()
    missing = sorted(set(pins) - set(files))
    if missing:
        raise DeckError(f"the fd_pv source lacks {', '.join(missing[:3])}{' ...' if len(missing) > 3 else ''} "
                        f"(expected {REPOSITORY} at {COMMIT[:7]})")
    for path, sha in pins.items():
        got = hashlib.sha256(files[path]).hexdigest()
        if got != sha:
            raise DeckError(f"{path} of the fd_pv source has sha256 {got[:16]}..., not the pinned {sha[:16]}... "
                            f"(another commit than {COMMIT[:7]}, or altered): refusing it; nothing installed")
    out = {p: files[p] for p in pins}
    by_file = {}
    for p in patches():
        if p.file in by_file or p.file not in pins:
            raise DeckError(f"patch {p.name}: {p.file} is {'patched twice' if p.file in by_file else 'not a pinned file'}")
        by_file[p.file] = p
        out[p.file] = patched(p.file, out[p.file], p)
    return out


def _write(files: dict) -> Path:
    """Install the checked files whole: a new folder beside the target, renamed into place."""
    target = install_dir()
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=target.parent))
    try:
        for path, data in files.items():
            dest = tmp / path
            dest.parent.mkdir(parents=True, exist_ok=True)
            dest.write_bytes(data)
        (tmp / "PIXELKIT_SOURCE").write_text(f"{SOURCE}; patched by pixelkit: "
                                             + ", ".join(p.name for p in patches()) + "\n")
        if target.exists():
            shutil.rmtree(target)
        os.replace(tmp, target)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return target


def install_from(source: Path) -> Path:
    """Install from a checkout / unpacked archive of the repository at :data:`COMMIT`."""
    source = Path(source)
    if not source.is_dir():
        raise DeckError(f"{source}: not a folder (expected a checkout of {REPOSITORY} at {COMMIT[:7]})")
    files = {}
    for path in pinned():
        f = source / path
        if f.is_symlink() or not f.is_file():
            raise DeckError(f"{source} has no file {path} (expected a checkout of {REPOSITORY} at {COMMIT[:7]})")
        files[path] = f.read_bytes()
    return _write(_verified(files))


def fetch(timeout: float = 60.0) -> Path:
    """Download the repository's archive at :data:`COMMIT` from GitHub and install the pinned files
    (a verified installation is kept as it is)."""
    if check() is None:
        return install_dir()
    import urllib.request
    try:
        with urllib.request.urlopen(ARCHIVE_URL, timeout=timeout) as r:
            blob = r.read(_MAX_ARCHIVE + 1)
    except OSError as exc:
        raise DeckError(f"could not download {ARCHIVE_URL} ({getattr(exc, 'reason', exc)})") from None
    if len(blob) > _MAX_ARCHIVE:
        raise DeckError(f"{ARCHIVE_URL} is larger than {_MAX_ARCHIVE >> 20} MB: refusing it")
    wanted, files = set(pinned()), {}
    try:
        with tarfile.open(fileobj=io.BytesIO(blob), mode="r:gz") as tar:
            for m in tar:
                rel = m.name.split("/", 1)[1] if "/" in m.name else ""
                if rel in wanted and m.isfile():
                    files[rel] = tar.extractfile(m).read()
    except (tarfile.TarError, OSError, EOFError) as exc:
        raise DeckError(f"{ARCHIVE_URL}: not a readable archive ({exc})") from None
    return _write(_verified(files))


def check() -> str | None:
    """None when the installed copy is complete and every file has its expected sha256; else why not."""
    root = install_dir()
    src = os.environ.get("PIXELKIT_FD_PV")
    if not root.is_dir() and src:
        try:
            install_from(Path(src))
        except DeckError as exc:
            return f"PIXELKIT_FD_PV={src}: {exc}"
    if not root.is_dir():
        return f"the {NAME} decks are not installed (looked for {root}): {FETCH_HINT}"
    for path, sha in expected().items():
        f = root / path
        if f.is_symlink() or not f.is_file():
            return f"{f} is missing from the installed {NAME} decks: {FETCH_HINT}"
        got = hashlib.sha256(f.read_bytes()).hexdigest()
        if got != sha:
            return (f"{f} is not the pinned file (sha256 {got[:16]}..., expected {sha[:16]}...): it was changed "
                    f"or damaged; it is not run. {FETCH_HINT}")
    return None


def deck(which: str = LVS_DECK) -> Path:
    """The verified installed deck ``which`` (a path of the repository)."""
    why = check()
    if why is not None:
        raise DeckError(why)
    return install_dir() / which
