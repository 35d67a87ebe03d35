"""The verdict first (issue 42): one exit rule for every verdict command, the report's banner and
exit status, every figure once (power at nominal, one unit, no absolute path of the machine).

Independent paths: the exit rule against the team's table (docs/cli-conventions.md), written
out here case by case; the report's verdict against the sign-off rows it was made from, read
back from ``signoff.csv`` (the CSV the section wrote, parsed here); the paths by looking on this
machine's disk for every absolute-path-like token of every file the report wrote; the power
condition against the design's own nominal (its corner, temperature and 0 % supply).
"""
import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest

from conftest import REF, REF_QUICK_WAVES, ROOT, run_cli


def test_report_verdict_follows_the_team_rule():
    """The report's verdict from sign-off rows, sections and diff (the rule itself: robust's tests in
    test_verify.py): a failing spec or diff 1, a failed section or unmeasured spec 5, a failed
    simulation 4 when nothing fails, no specs and nothing else 0."""
    from pixelkit.report.verdict import verdict
    ok = {"sections": {"a": "available"}, "profile": "full"}

    def row(st):
        return {"spec": st, "status": st}
    assert verdict(ok, {"rows": [row("pass")]})["exit"] == 0
    assert verdict(ok, {"rows": [row("pass"), row("not run")]})["exit"] == 5
    assert verdict(ok, {"rows": [row("fail"), row("not run")]})["verdict"] == "FAIL"
    assert verdict(ok, {"rows": [row("pass")], "errors": [{}]})["exit"] == 4
    assert verdict(ok, {"rows": [row("pass")]}, {"passed": False})["exit"] == 1
    assert verdict({"sections": {"a": "failed"}, "profile": "quick"}, None)["exit"] == 5
    v = verdict(ok, None)
    assert (v["verdict"], v["exit"]) == ("NO SPECS", 0)


def _signoff_csv(out: Path) -> list[dict]:
    with (out / "signoff.csv").open() as f:
        return list(csv.DictReader(f))


def test_report_verdict_banner_and_exit(quick_report):
    out, q = quick_report["out"], quick_report
    rows = _signoff_csv(out)
    failing = [r["spec"] for r in rows if r["status"] == "fail"]
    unmeasured = [r["spec"] for r in rows if r["status"] in ("not measured", "not run")]
    v = json.loads((out / "summary.json").read_text())["verdict"]
    # the reference passes what its nominal condition measures (its failures are at other conditions of
    # its grid, docs/verify.md) and the nominal-only profile does not run its 85 degC spec: NOT MEASURED,
    # exit 5 (the FAIL banner: test_report.py::test_revision_diff_names_the_changed_device_and_fails_on_specs)
    assert not failing and unmeasured == ["pd_dark_drop_secondary"]
    assert q["code"] == 5 and v["verdict"] == "NOT MEASURED" and v["exit"] == 5
    assert [x["spec"] for x in v["failing"]] == failing
    assert [x["spec"] for x in v["not_measured"]] == unmeasured
    assert v["passing"] == sum(r["status"] == "pass" for r in rows) and v["specs"] == len(rows)
    assert (v["view"], v["profile"], v["conditions"]) == ("schematic", "nominal only", 1)
    # the terminal says it first, nominal only included
    lines = q["stdout"].splitlines()
    assert lines[1].startswith(f"  NOT MEASURED: {v['passing']} of {len(rows)} specs pass (schematic, nominal only")
    assert any(ln.strip().startswith("NOT RUN pd_dark_drop_secondary:") for ln in lines)
    for name in failing:
        worst = next(r["worst condition"] for r in rows if r["spec"] == name)
        assert any(ln.strip().startswith(f"FAIL {name}:") and worst in ln for ln in lines), name
    # the page: the banner before the table of contents, each failing spec linked to its row,
    # whose status cell carries the class the style colours
    page = (out / "index.html").read_text()
    banner = page[page.index('<section id="verdict" class="banner unmeasured"'):page.index('<nav class="toc">')]
    assert "pd_dark_drop_secondary" in banner
    for name in failing:
        assert f'href="#spec-{name}"' in banner
        row = re.search(rf'<tr id="spec-{name}" class="fail">(.*?)</tr>', page, re.S).group(1)
        assert '<td class="status fail">FAIL</td>' in row
    assert "nominal only" in banner


def test_quick_option_says_nominal_only():
    _, text, _ = run_cli("report", "--help")
    assert "nominal only" in " ".join(text.split())


#: an absolute path as a file would carry it: a slash after a quote, a space, '(' or '=', then
#: two or more folder names
ABSOLUTE = re.compile(r"""(?:(?<=["'\s(=])|^)(/[A-Za-z0-9._-]+(?:/[A-Za-z0-9._+-]+)+)""", re.M)


def test_no_absolute_path_of_this_machine_in_any_output(quick_report):
    """Every text file the report wrote: no token that names a folder existing on this machine (the
    staging folder the report was built in counts: it existed while the report was written)."""
    out = quick_report["out"]
    found = []
    for f in sorted(out.rglob("*")):
        if not f.is_file() or f.suffix.lower() in (".png", ".gds", ".npz", ".pdf"):
            continue
        text = f.read_text(errors="replace")
        for m in ABSOLUTE.finditer(text):
            p = Path(m.group(1))
            if any(part.startswith(f".{out.name}.new-") for part in p.parts) or p.parent.exists():
                found.append(f"{f.relative_to(out)}: {m.group(1)}")
    assert not found, found[:20]


def test_portable_rewrites_paths_under_the_stage_cache_and_home(tmp_path, monkeypatch):
    from pixelkit.report.portable import _roots, portable
    monkeypatch.setenv("PIXELKIT_CACHE", str(tmp_path / "cache"))
    stage = tmp_path / ".r.new-1"
    roots = _roots(stage)
    x = {"a": [f"{stage}/lvs/X.lvsdb", f"deck {tmp_path}/cache/decks/gf.drc", f"{Path.home()}/d.drc"]}
    assert portable(x, roots) == {"a": ["lvs/X.lvsdb", "deck $PIXELKIT_CACHE/decks/gf.drc", "~/d.drc"]}
    # KLayout's DRC database names the kit's deck runner by its absolute path (seen in a full report's
    # layout_signoff/drc/CHIP_2X2_AFE.lyrdb): the file is rewritten like the section's text
    from pixelkit.report.portable import portable_section
    from pixelkit.report.sections import Section
    kit = ROOT / "pixelkit" / "layout" / "signoff" / "deck_runner.drc"
    (stage / "drc").mkdir(parents=True)
    (stage / "drc" / "C.lyrdb").write_text(f"<generator>klayout -r '{kit.resolve()}'</generator>")
    s = Section("t", files=["drc/C.lyrdb"])
    portable_section(s, stage)
    assert (stage / "drc" / "C.lyrdb").read_text() == "<generator>klayout -r 'pixelkit/layout/signoff/deck_runner.drc'</generator>"


def test_power_at_the_nominal_condition_and_fractions_in_percent(quick_report, ref_design):
    out = quick_report["out"]
    data = json.loads((out / "data_signoff.json").read_text())
    corner = ref_design.corner_name
    assert data["power"]["condition"].startswith(f"{corner} {ref_design.temperature - 273.15:g}degC")
    assert data["power"]["condition"].endswith("+0%")
    caption = json.loads((out / "tables.json").read_text())["signoff_power"]["caption"]
    assert "nominal condition" in caption and data["power"]["condition"] in caption
    checked = json.loads((out / "summary.json").read_text())["checked"]
    assert not [k for k, c in checked.items() if k.endswith("_frac")]
    g = checked["afe.gain_error_pct"]
    assert g["unit"] == "%"
    # the AFE table gives the same figure in %
    rows = json.loads((out / "tables.json").read_text())["afe_summary"]["rows"]
    table = next(r[1] for r in rows if r[0].startswith("gain error, SPICE fit (%)"))
    assert g["value"] == pytest.approx(table, rel=1e-9)
    assert f"AFE gain error           {g['value']:.4g} %" in quick_report["stdout"]


def test_a_baseline_fraction_compares_with_todays_percent():
    from pixelkit.report.diff import _checked
    old = {"afe.gain_error_frac": {"value": -0.002, "unit": "1", "tol_rel": 0.05, "tol_abs": 2e-4}}
    new = {"afe.gain_error_pct": {"value": -0.2, "unit": "%", "tol_rel": 0.05, "tol_abs": 0.02, "section": "afe"}}
    (row,) = _checked(old, new)
    assert row["figure"] == "afe.gain_error_pct" and row["status"] == "same" and row["tolerance"] == pytest.approx(0.02)


def test_the_readme_and_conventions_say_report_exits_as_verify():
    conv = " ".join((ROOT / "docs" / "cli-conventions.md").read_text().split())
    assert "| 5 |" in conv and "`pixelkit report` exits as `pixelkit verify` does" in conv
    readme = " ".join((ROOT / "README.md").read_text().split())
    assert "5 nothing failed but something asked was not measured" in readme
    assert "exit 1 when a spec fails, as `verify`" in readme


def test_failing_specs_have_their_waveform_with_the_measurements_readings(quick_report):
    """Each failing spec and each spec asked for (the session's report asks for two, none failing at
    nominal: ``REF_QUICK_WAVES``): the decks its measurement ran, written as raw files that read back (the
    kit's raw reader, and the command that opens them), and the readings marked on the traces: a
    marked level is the trace's value at the marked instant (interpolated from the raw file, an
    independent read of the same numbers), and for the PD-referred conversion gain the two PD
    readings give the figure's own drop."""
    from pixelkit.spice.raw import read_raw
    out = quick_report["out"]
    data = json.loads((out / "data_signoff.json").read_text())
    failing = [r["spec"] for r in data["rows"] if r["status"] == "fail"]
    shown = sorted(set(failing) | set(REF_QUICK_WAVES))
    assert sorted(data["waves"]) == shown
    for name, w in data["waves"].items():
        assert w["files"] and w["marks"], name
        for f in w["files"]:
            (plot,) = read_raw(out / f)
            deck = f.rsplit("_vfy_", 1)[1][:-4]
            for m in (m for m in w["marks"] if m["deck"] == "vfy_" + deck):
                v = np.interp(m["t"], plot["data"]["time"], plot["data"][f"v({m['node']})"])
                assert v == pytest.approx(m["v"], abs=1e-9), (name, m)
        page = (out / "index.html").read_text()
        assert f'id="wave-{name}"' in page and f'id="plot-{name}"' in page
    assert page.count("Plotly.newPlot") == len(shown) and page.count("<script>/**") <= 1
    w = data["waves"]["pd_conversion_gain_secondary"]
    pd = [m for m in w["marks"] if m["deck"] == "vfy_small"]
    assert [m["what"] for m in pd] == ["PD after reset", "PD before transfer"]


def test_waves_opens_a_raw_file_and_refuses_bad_paths(quick_report, tmp_path):
    out = quick_report["out"]
    raw = out / json.loads((out / "data_signoff.json").read_text())["waves"]["full_well_primary"]["files"][0]
    code, stdout, err = run_cli("waves", raw, "--out", tmp_path / "w.html", "--json")
    assert code == 0, err
    page = (tmp_path / "w.html").read_text()
    markup = re.sub(r"<script>.*?</script>", "", page, flags=re.S)   # plotly.js inlined: its text names URLs
    assert "Plotly.newPlot" in page and "v(col_p)" in page and not re.search(r"(src|href)=\"https?://", markup)
    assert page.count("<script") == 2 and '<script src' not in page   # the library once, the figure's call
    for bad, what in ((tmp_path / "none.raw", "RAW"), (tmp_path, "RAW"), (raw.with_suffix(".txt"), "RAW")):
        code, _, err = run_cli("waves", bad)
        assert code == 2 and what in err, err
    junk = tmp_path / "junk.raw"
    junk.write_bytes(b"Title: x\nNo. Variables: 2\nNo. Points: 5\nVariables:\n\t0\ttime\ttime\n")
    code, _, err = run_cli("waves", junk)
    assert code == 2 and "junk.raw" in err, err
    code, _, err = run_cli("waves", raw, "--vectors", "v(nowhere)")
    assert code == 2 and "--vectors" in err


def test_lightmap_verdict_judges_the_error_against_its_limit():
    """The rule alone (the light map's currents come from elsewhere): |error| against k x the read
    noise or a voltage, exit 1 beyond it, exactly at the limit a pass; bad limits refused naming
    --max-error."""
    from pixelkit.errors import ConfigError
    from pixelkit.verify.light import judge
    cols = {"col_p": {"error_V": -3e-3, "read_noise_V": 2e-3}, "col_s0": {"error_V": 1e-3, "read_noise_V": 1e-3}}
    v = judge(cols, "1x")
    assert (v["verdict"], v["exit"], v["failed"]) == ("FAIL", 1, ["col_p"])
    assert v["columns"]["col_s0"]["status"] == "pass" and v["columns"]["col_p"]["margin_V"] == pytest.approx(-1e-3)
    assert judge(cols, "1.5x")["exit"] == 0 and judge(cols, "3 mV")["exit"] == 0 and judge(cols, "2.9 mV")["exit"] == 1
    for bad in ("0x", "-1x", "x", "3 uA", "1e9 V", "nan x"):
        with pytest.raises(ConfigError, match="--max-error"):
            judge(cols, bad)


def test_a_drc_result_names_its_deck_by_the_decks_folder_not_this_machine(monkeypatch, tmp_path):
    """`pixelkit signoff --json` and its signoff.json printed the DRC deck as /root/.cache/...: the deck
    in the decks' folder is named by that folder as the user sets it; a deck kept elsewhere (a
    technology file's own path) as configured."""
    from pixelkit.layout.signoff.drc import DrcResult

    def deck(path):
        return DrcResult(str(path), "TOP", {}, 1.0, "KLayout 0.28.5").as_dict()["deck"]
    monkeypatch.setenv("PIXELKIT_DECKS", str(tmp_path / "d"))
    assert deck(tmp_path / "d" / "gf180mcu.drc") == "$PIXELKIT_DECKS/gf180mcu.drc"
    monkeypatch.delenv("PIXELKIT_DECKS")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "x"))
    assert deck(tmp_path / "x" / "pixelkit" / "decks" / "a.drc") == "$XDG_CACHE_HOME/pixelkit/decks/a.drc"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "h"))
    assert deck(tmp_path / "h" / ".cache" / "pixelkit" / "decks" / "a.drc") == "~/.cache/pixelkit/decks/a.drc"
    assert deck(tmp_path / "decks2" / "a.drc") == str(tmp_path / "decks2" / "a.drc")   # not the decks' folder
    assert deck(tmp_path / "h" / ".cache" / "pixelkit" / "decksX" / "a.drc").startswith(str(tmp_path))
