"""The report in a real browser with the network off (issue 42): headless Chromium loads a failing
quick report (the reference with a spec its nominal condition misses, conftest's ``failing_report``)
and its datasheet; the page itself reports (``docsite.browser``'s
probe) the verdict banner's colour and text, a failing spec's status colour, each waveform drawn
by plotly and answering a zoom and a legend click, script errors and failed resources. The
colours are read as the browser computed them, against the style's values written out here; the
text against the sign-off rows parsed from ``signoff.csv``. The docs' screenshots are taken by
the same code (``docsite.screenshots``), run here on this report.
"""
import csv
import json
import re
import sys

import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT))
from docsite import browser, screenshots  # noqa: E402

RED, GREEN = "rgb(179, 38, 30)", "rgb(30, 123, 52)"
FAIL_CELL, PASS_CELL = "rgb(251, 224, 221)", "rgb(227, 243, 231)"


@pytest.fixture(scope="module")
def seen(failing_report):
    out = failing_report["out"]
    with (out / "signoff.csv").open() as f:
        rows = list(csv.DictReader(f))
    failing = [r["spec"] for r in rows if r["status"] == "fail"]
    passing = next(r["spec"] for r in rows if r["status"] == "pass")
    sels = ["#verdict", "#table-signoff", "main", f"tr#spec-{failing[0]} td.status", f"tr#spec-{passing} td.status",
            *(f"#wave-{s}" for s in failing)]
    return out, rows, failing, passing, browser.probe(out / "index.html", sels, 1400)


def test_no_error_and_no_network(seen):
    *_, p = seen
    assert p["errors"] == [] and p["console"] == [], (p["errors"], p["console"][:5])


def test_banner_says_fail_in_red_first(seen):
    out, rows, failing, _, p = seen
    b = p["boxes"]["#verdict"]
    assert b["bg"] == RED and b["color"] == "rgb(255, 255, 255)"
    passing = sum(r["status"] == "pass" for r in rows)
    text = " ".join(b["text"].split())
    assert text.startswith(f"FAIL {passing} of {len(rows)} specs pass") and "nominal only" in text
    assert "schematic" in text and all(s in text for s in failing)
    assert b["y"] < p["boxes"]["#table-signoff"]["y"]


def test_failing_status_is_red_passing_green_and_the_table_fits_1400px(seen):
    _, _, failing, passing, p = seen
    bad, good = p["boxes"][f"tr#spec-{failing[0]} td.status"], p["boxes"][f"tr#spec-{passing} td.status"]
    assert (bad["bg"], bad["color"], bad["text"]) == (FAIL_CELL, RED, "FAIL")
    assert (good["bg"], good["color"], good["text"]) == (PASS_CELL, GREEN, "PASS")
    table, main = p["boxes"]["#table-signoff"], p["boxes"]["main"]
    assert table["x"] >= main["x"] and table["x"] + table["w"] <= main["x"] + main["w"] + 0.5
    assert p["width"] <= p["client"], "the page scrolls sideways at 1400 px"


def test_every_failing_spec_has_an_interactive_waveform(seen):
    _, _, failing, _, p = seen
    assert p["plotly"] and sorted(x["id"] for x in p["plots"]) == sorted(f"plot-{s}" for s in failing)
    assert all(x["svg"] > 0 and x["traces"] >= 2 for x in p["plots"]), p["plots"]
    z = p["zoom"]
    assert z["after"] != z["before"] and z["after"][1] - z["after"][0] < (z["before"][1] - z["before"][0]) / 2
    assert p["hidden"] == "legendonly"


def test_datasheet_renders_on_one_page(failing_report):
    out = failing_report["out"]
    s = browser.probe(out / "datasheet.html", ["#ds-verdict", "#ds-specs", "#ds-layout"], 820)
    assert s["errors"] == [] and s["console"] == []
    assert s["boxes"]["#ds-verdict"]["bg"] == RED and s["boxes"]["#ds-verdict"]["text"].startswith("FAIL")
    assert "match" in s["boxes"]["#ds-layout"]["text"]
    pdf = (out / "datasheet.pdf").read_bytes()
    assert pdf.startswith(b"%PDF") and len(re.findall(rb"/Type\s*/Page[^s]", pdf)) == 1
    summary = json.loads((out / "summary.json").read_text())
    assert summary["datasheet"] == {"html": "datasheet.html", "pdf": "datasheet.pdf", "why": ""}


def test_the_docs_screenshots_come_from_this_code(failing_report, tmp_path):
    from PIL import Image
    pics = screenshots.take(failing_report["out"], tmp_path)
    assert [p.name for p in pics] == ["report_banner.png", "report_signoff.png", "report_waveform.png",
                                      "datasheet.png"]
    with Image.open(pics[0]) as im:   # the banner's picture is the banner: mostly its red
        red = sum(1 for px in im.convert("RGB").get_flattened_data() if px == (179, 38, 30))
        assert red > 0.5 * im.width * im.height
    for p in pics:
        assert (ROOT / "docs" / p.name).is_file(), f"docs/{p.name} missing: python -m docsite.screenshots REPORT docs"
