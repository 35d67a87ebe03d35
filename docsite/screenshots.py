"""The report's pictures in the docs, taken from a report by the browser the test uses.

    python -m docsite.screenshots REPORT_DIR [DOCS_DIR]

writes ``report_banner.png`` (the verdict), ``report_signoff.png`` (the sign-off table, a failing
spec's row red), ``report_waveform.png`` (the first failing spec's waveform) and
``datasheet.png`` (the datasheet page) into DOCS_DIR (default ``docs/``). Make them from the quick
report of the reference design (``pixelkit report designs/dual_pixel_revA.toml --quick``); the
browser test (``tests/test_report_browser.py``) runs this on its own report, so it keeps working.
"""
from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

from docsite import browser

WIDTH = 1400


def take(report: Path, docs: Path) -> list[Path]:
    report, docs = Path(report), Path(docs)
    data = json.loads((report / "data_signoff.json").read_text())
    failing = [r["spec"] for r in data["rows"] if r["status"] == "fail"]
    sels = ["#verdict", "#table-signoff"] + [f"#wave-{failing[0]}"] if failing else ["#verdict", "#table-signoff"]
    seen = browser.probe(report / "index.html", sels, WIDTH)
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        full = browser.screenshot(report / "index.html", Path(tmp) / "full.png", WIDTH, min(seen["height"], 16000))
        out.append(browser.crop(full, seen["boxes"]["#verdict"], docs / "report_banner.png"))
        out.append(browser.crop(full, seen["boxes"]["#table-signoff"], docs / "report_signoff.png", max_h=520))
        if failing:
            out.append(browser.crop(full, seen["boxes"][f"#wave-{failing[0]}"], docs / "report_waveform.png"))
        sheet = browser.screenshot(report / "datasheet.html", Path(tmp) / "sheet.png", 820, 1160)
        out.append(browser.crop(sheet, {"x": 0, "y": 0, "w": 820, "h": 1160}, docs / "datasheet.png", pad=0))
    return out


if __name__ == "__main__":
    for p in take(Path(sys.argv[1]), Path(sys.argv[2]) if len(sys.argv) > 2 else Path("docs")):
        print(p)
