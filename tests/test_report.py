"""The design report (issue 13, must show): it renders in a real browser, and the revision diff.

The browser check is independent of the code under test: headless Chromium (Debian's
``chromium``) loads the written ``index.html`` and the page itself reports, from the DOM,
which images failed to decode (``naturalWidth == 0``), how many rows each table has and
which script errors happened. The diff is checked against a design change made here
(the pixel SF width, a field the report never sees except through the design file).
"""
import html.parser
import json
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from conftest import REF, REF_QUICK_EXIT, run_cli

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"

#: Injected into a copy of the page: collects script errors and, after load, writes what the
#: browser saw into a <pre id="pk-probe"> that --dump-dom prints.
PROBE = """<script>
window.__pkErrors = [];
window.addEventListener('error', function (e) {
  window.__pkErrors.push('error: ' + (e.message || (e.target && (e.target.src || e.target.href)) || 'resource'));
}, true);
var _ce = console.error;
console.error = function () { window.__pkErrors.push('console.error: ' + Array.from(arguments).join(' ')); };
window.addEventListener('load', function () {
  var imgs = Array.from(document.images);
  var out = {
    images: imgs.length,
    broken: imgs.filter(function (i) { return !i.complete || i.naturalWidth === 0; })
                .map(function (i) { return i.getAttribute('src'); }),
    tables: Array.from(document.querySelectorAll('table')).map(function (t) {
      return {id: t.id, rows: t.querySelectorAll('tbody tr, tr').length,
              body_rows: Array.from(t.querySelectorAll('tr')).filter(function (r) {
                return r.querySelector('td'); }).length};
    }),
    errors: window.__pkErrors
  };
  var pre = document.createElement('pre');
  pre.id = 'pk-probe';
  pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
});
</script>"""


def chromium(*args, timeout=120):
    profile = Path(__import__("tempfile").mkdtemp(prefix="pk-chromium-"))
    try:
        return subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                               "--no-first-run", "--disable-background-networking", "--disable-component-update",
                               "--disable-sync", f"--user-data-dir={profile}", *args],
                              capture_output=True, text=True, timeout=timeout)
    finally:
        shutil.rmtree(profile, ignore_errors=True)


@pytest.fixture(scope="module")
def quick_report(quick_report):
    """The session's quick report of the reference design (conftest.py): (folder, stdout)."""
    return quick_report["out"], quick_report["stdout"]


class _Srcs(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.srcs, self.links = [], []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.srcs.append(a.get("src"))
        if tag in ("link", "script") and (a.get("href") or a.get("src")):
            self.links.append(a.get("href") or a.get("src"))


def test_report_prints_where_it_is_and_a_summary(quick_report):
    """Format only: the CG pair is checked below, the AFE error, sizing, array and layout figures in
    test_report_sections.py, each against its reference."""
    out, stdout = quick_report
    assert str(out / "index.html") in stdout
    summary = json.loads((out / "summary.json").read_text())
    assert summary["checked"], "summary.json lists no checked figure"
    # every checked figure in summary.json is a finite number with a unit
    for name, c in summary["checked"].items():
        assert isinstance(c["value"], float) and c["value"] == c["value"], name


def test_every_checked_name_has_a_registered_reference(quick_report):
    """The concrete names of the quick report's summary.json, each covered by a test of the registry
    (tests/figure_references.py; its walk over the code is tests/test_figure_references.py)."""
    from figure_references import uncovered_names
    out, _ = quick_report
    names = json.loads((out / "summary.json").read_text())["checked"]
    assert len(names) > 10
    assert uncovered_names(names) == []


def test_report_output_cg_pair_against_the_analytic_level(quick_report):
    """Independent reference: the other level. The report's SPICE output-referred CG_out(0-30 %)
    (slope of the column signal against I t_window below 30 % of swing) against the analytic
    CG_out(0) = A_sf q / C of the PD node + FD at the reset bias (C(V) junctions; A_sf from two SPICE operating points,
    no transient). C rises as the node discharges, so the SPICE slope sits below the
    zero-signal figure, by at most 3 %."""
    out, _ = quick_report
    c = json.loads((out / "summary.json").read_text())["checked"]
    for w in ("primary", "secondary"):
        spice = c[f"summary.{w}.cg_out_0_30_uV_per_e"]["value"]
        physics = c[f"summary.{w}.cg_out_0_uV_per_e"]["value"]
        assert 0.97 * physics <= spice <= physics, (w, spice, physics)
    # the pair: a secondary electron moves the column ~2.8x as far (the smaller PD node)
    ratio = (c["summary.secondary.cg_out_0_30_uV_per_e"]["value"]
             / c["summary.primary.cg_out_0_30_uV_per_e"]["value"])
    physics_ratio = (c["summary.secondary.cg_out_0_uV_per_e"]["value"]
                     / c["summary.primary.cg_out_0_uV_per_e"]["value"])
    assert ratio == pytest.approx(physics_ratio, rel=0.02)


def test_report_renders_in_chromium_images_tables_no_errors(quick_report):
    out, _ = quick_report
    page = (out / "index.html").read_text()
    parser = _Srcs()
    parser.feed(page)
    assert parser.srcs, "the report has no picture"
    assert not parser.links, f"the report loads external resources: {parser.links}"
    markup = re.sub(r"<script>.*?</script>", "", page, flags=re.S)   # plotly.js inlined: its text names URLs
    assert not re.search(r"(src|href)=\"https?://", markup), "the report refers to the network"
    missing = [s for s in parser.srcs if not (out / s).is_file()]
    assert not missing, f"pictures missing beside the HTML: {missing}"
    probe_page = out / "_probe.html"
    probe_page.write_text(page.replace("<head>", "<head>" + PROBE, 1))
    assert PROBE in probe_page.read_text()
    p = chromium("--enable-logging=stderr", "--v=0", "--virtual-time-budget=10000", "--dump-dom",
                 probe_page.as_uri())
    probe_page.unlink()
    m = re.search(r'<pre id="pk-probe">(.*?)</pre>', p.stdout, re.S)
    assert m, f"Chromium did not run the page's load handler: {p.stderr[-2000:]}"
    seen = json.loads(html.unescape(m.group(1)))
    assert seen["images"] == len(parser.srcs)
    assert seen["broken"] == [], f"images that did not load: {seen['broken']}"
    assert seen["tables"], "no table rendered"
    empty = [t["id"] for t in seen["tables"] if t["body_rows"] == 0]
    assert not empty, f"tables without rows: {empty}"
    assert seen["errors"] == [], seen["errors"]
    # its one script is plotly's (the waveforms): any console line Chromium logs is a fault
    console = [ln for ln in p.stderr.splitlines() if "CONSOLE" in ln or "Uncaught" in ln]
    assert not console, console


def test_revision_diff_names_the_changed_device_and_fails_on_specs(quick_report, tmp_path):
    """A narrower SF (0.6 um; 1 um in revA, a wider one breaks the layout rule transistors_fit) and a
    30 dB op-amp: the diff names both fields, the figures they moved and the netlists they changed,
    and (revA has specs) fails on the spec the low gain breaks (AFE gain error 6 % > 0.5 %), ranked
    first, not on the figures that moved."""
    base, _ = quick_report
    changed = tmp_path / "revB.toml"
    text = re.sub(r'^sf_w = "1 um"', 'sf_w = "0.6 um"', REF.read_text(), flags=re.M)
    text = re.sub(r'^gain = "60 dB"', 'gain = "30 dB"', text, flags=re.M)
    assert text.count("0.6 um") > REF.read_text().count("0.6 um") and "30 dB" in text
    changed.write_text(text)
    code, stdout, err = run_cli("report", changed, "--quick", "--out", tmp_path / "revB", "--baseline", base)
    assert code == 1, err + stdout
    diff = json.loads((tmp_path / "revB" / "diff.json").read_text())
    assert [c["field"] for c in diff["design_changes"]] == ["afe.gain", "pixel.devices.sf_w"]
    assert diff["by_specs"] and not diff["passed"] and diff["newly_failing"] == ["afe_gain_error"]
    assert diff["specs"][0]["spec"] == "afe_gain_error" and diff["specs"][0]["verdict"] == "newly failing"
    # the SF's gain sets the output-referred conversion gain: it must be among what moved
    assert any("cg_out" in name for name in diff["moved"]), diff["moved"]
    assert any(n["status"] == "changed" for n in diff["netlists"]), "no generated netlist changed"
    assert "pixel.devices.sf_w" in stdout and "NEWLY FAILING  afe_gain_error" in stdout
    # the verdict: FAIL first on the terminal and in the banner, the failing spec linked to its row,
    # whose status cell carries the class the style colours
    assert stdout.splitlines()[1].startswith("  FAIL: ") and "FAIL afe_gain_error:" in stdout
    page = (tmp_path / "revB" / "index.html").read_text()
    banner = page[page.index('<section id="verdict" class="banner fail"'):page.index('<nav class="toc">')]
    assert 'href="#spec-afe_gain_error"' in banner
    row = re.search(r'<tr id="spec-afe_gain_error" class="fail">(.*?)</tr>', page, re.S).group(1)
    assert '<td class="status fail">FAIL</td>' in row


def test_intentional_change_moves_figures_and_passes_on_specs_ranked(quick_report, tmp_path):
    """Issue 31's case: a longer SF (sf_l 0.5 -> 0.8 um; 1 um no longer fits the secondary's 8 um
    cell, layout rule transistors_fit) moves checked figures (the pedestal follows the SF's V_GS)
    and breaks no spec: the diff lists what moved, ranks the specs by the margin the revision used
    and passes, exit 0. Judged by moved figures (the rule of a design without specs) it would fail."""
    base, _ = quick_report
    changed = tmp_path / "revB.toml"
    text = re.sub(r'^sf_l = "0.5 um"', 'sf_l = "0.8 um"', REF.read_text(), flags=re.M)
    assert text != REF.read_text()
    changed.write_text(text)
    code, stdout, err = run_cli("report", changed, "--quick", "--out", tmp_path / "revB", "--baseline", base)
    # exit 5 all the same: no spec fails at nominal, the 85 degC one is not run, as in the baseline
    assert code == REF_QUICK_EXIT == 5, err + stdout
    assert _failing(tmp_path / "revB") == _failing(base) == []
    diff = json.loads((tmp_path / "revB" / "diff.json").read_text())
    assert [c["field"] for c in diff["design_changes"]] == ["pixel.devices.sf_l"]
    assert any("pedestal" in name for name in diff["moved"]), diff["moved"]
    assert diff["by_specs"] and diff["passed"] and diff["newly_failing"] == []
    # the quick profile runs the nominal condition only: an 85 degC spec is "not run", unranked
    assert all(r["verdict"] == "not run" for r in diff["specs"] if r.get("margin_used_pct") is None)
    used = [r["margin_used_pct"] for r in diff["specs"] if r.get("margin_used_pct") is not None]
    assert len(used) >= 8 and used == sorted(used, reverse=True), used
    assert "no spec newly failing" in stdout
    _, help_text, _ = run_cli("report", "--help")
    assert "newly fails" in " ".join(help_text.split())


def _failing(folder) -> list[str]:
    return [x["spec"] for x in json.loads((folder / "summary.json").read_text())["verdict"]["failing"]]


def test_unchanged_revision_diff_passes_and_json_gives_it_without_html(quick_report, tmp_path):
    """The diff of an unchanged revision passes; the command exits 5 all the same, on revA's own
    spec the nominal-only profile does not run (the verdict is the design's, the diff's is said beside
    it)."""
    base, _ = quick_report
    out = tmp_path / "again"
    code, stdout, err = run_cli("report", REF, "--quick", "--out", out, "--baseline", base, "--json")
    assert code == REF_QUICK_EXIT, err + stdout
    r = json.loads(stdout)
    assert r["verdict"]["verdict"] == "NOT MEASURED" and not r["verdict"]["diff_failed"]
    assert r["html"] is None and not (out / "index.html").exists()
    assert r["diff"]["passed"] and r["diff"]["moved"] == [] and r["diff"]["design_changes"] == []
    assert all(c["status"] == "same" for c in r["diff"]["checked"])


def _golden_elements(path: Path) -> dict:
    """{subckt: {element: nets}} parsed from a golden deck's text (not from the Netlist objects)."""
    out, sub = {}, None
    for line in path.read_text().splitlines():
        words = line.split()
        if not words or line.startswith("*"):
            continue
        if words[0] == ".subckt":
            sub = out.setdefault(words[1], {})
        elif words[0] == ".ends":
            sub = None
        elif sub is not None and not words[0].startswith("."):
            plain = [w for w in words[1:] if "=" not in w]
            letter = words[0][0].upper()
            nets = plain[:-1] if letter == "X" else plain[:4] if letter in "EG" else plain[:2]
            sub[words[0]] = " ".join(nets)
    return out


def test_schematics_draw_every_element_of_the_golden_netlists(quick_report):
    """Independent path: the committed golden decks (netlists/*.cir) parsed as text here; every
    element of the 5T pixel and the SC AFE must be in the schematic's element table with the
    same nets, and each subcircuit's picture and element count must be there."""
    out, _ = quick_report
    import csv
    rows = list(csv.DictReader((out / "schematic_elements.csv").open()))
    drawn = {}
    for r in rows:
        drawn.setdefault(r["subcircuit"], {})[r["element"]] = r["nets"]
    root = REF.parents[1] / "netlists"
    for deck, sub in (("pixel5t_primary.cir", "pix5t_primary"), ("sc_afe.cir", "scafe"),
                      ("dual_pixel.cir", "dualpix")):
        golden = _golden_elements(root / deck)[sub]
        assert len(golden) >= 4
        assert drawn[sub] == golden, sub
        assert (out / f"schematic_{sub}.png").is_file()
        checked = json.loads((out / "summary.json").read_text())["checked"]
        assert checked[f"schematics.{sub}.elements"]["value"] == len(golden)
