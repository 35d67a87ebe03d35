"""The datasheet: the sign-off of one revision on one printable page (``datasheet.html``, and
``datasheet.pdf`` printed by headless Chromium where it is installed: ``setup.sh`` installs it).

It repeats, never recomputes: the verdict (``report.verdict``), the spec table, the conditions and
the Monte Carlo of the sign-off section, power at the nominal condition, the layout's DRC / LVS
status (layout sign-off section), the light map's verdict (light-map section), the revision and
the kit's commit (reproducibility section). A section that did not run says so in its place.
"""
from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

from .html import _ENV, fmt

#: Chromium's flags for printing (no network, no profile of the user's; the sandbox needs a user
#: namespace the kit cannot count on, as root in CI it refuses to start without --no-sandbox)
CHROMIUM_FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync",
                  "--no-pdf-header-footer")


def _table(sections, key: str, name: str):
    s = sections.get(key)
    return next((t for t in s.tables if t.name == name), None) if s is not None and s.available else None


def _layout(sections) -> dict:
    s = sections.get("layout_signoff")
    if s is None or not s.available:
        return {"available": False, "why": s.why if s is not None else "no layout sign-off section"}
    drc, lvs = s.data.get("drc"), s.data.get("lvs") or {}
    return {"available": True, "top": s.data.get("top"),
            "drc": "not run (quick profile)" if drc is None else
                   ("clean" if drc["clean"] else f"{drc['total']} violation(s)") + f" ({drc['deck']})",
            "lvs": "match" if lvs.get("match") else f"{len(lvs.get('mismatches', []))} mismatch(es)"}


def _light(sections) -> dict:
    s = sections.get("light_map")
    if s is None or not s.available:
        return {"available": False, "why": s.why if s is not None else "no light-map section"}
    return {"available": True, "verdict": s.data.get("verdict", {})}


def _commit(sections) -> str:
    t = _table(sections, "reproducibility", "repro_simulation")
    return next((r[1] for r in (t.rows if t else []) if r[0] == "pixelkit source (git)"), "unknown")


def render(folder: Path, design, sections: list, summary: dict) -> Path:
    by_key = {s.key: s for s in sections}
    so = by_key.get("signoff")
    signoff = so.data if so is not None and so.available else None
    css = (Path(__file__).parent / "templates" / "datasheet.css").read_text()
    html = _ENV.get_template("datasheet.html.j2").render(
        design=design, summary=summary, v=summary.get("verdict") or {}, signoff=signoff,
        layout=_layout(by_key), light=_light(by_key), commit=_commit(by_key), css=css, f=fmt)
    path = Path(folder) / "datasheet.html"
    path.write_text(html)
    return path


def print_pdf(html: Path, timeout: float = 120) -> tuple[Path | None, str]:
    """``datasheet.pdf`` beside ``html`` printed by headless Chromium: (path, "") or (None, why not)."""
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        return None, "Chromium is not installed (setup.sh installs it): no PDF, the HTML prints from a browser"
    pdf = html.with_suffix(".pdf")
    profile = tempfile.mkdtemp(prefix="pk-chromium-")
    try:
        p = subprocess.run([exe, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", f"--print-to-pdf={pdf}",
                            html.resolve().as_uri()], capture_output=True, text=True, timeout=timeout,
                           stdin=subprocess.DEVNULL)
    except (OSError, subprocess.SubprocessError) as exc:
        return None, f"Chromium did not print it ({type(exc).__name__})"
    finally:
        shutil.rmtree(profile, ignore_errors=True)
    if p.returncode != 0 or not pdf.is_file() or pdf.stat().st_size == 0:
        return None, f"Chromium did not print it (exit {p.returncode})"
    return pdf, ""
