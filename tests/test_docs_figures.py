"""Every number a docs page marks as quoted from the kit (``docsite/figures.py``) is the kit's
current output at the digits quoted: the session's quick report of the reference design is the
reference (the kit's own output, which is what the page claims to quote). The checker is shown to
fail on a planted stale figure, on a key that names nothing and on a marker not after a number,
and ``--update`` to rewrite a stale figure with the same digits."""
import json
import sys

from conftest import ROOT

sys.path.insert(0, str(ROOT))
from docsite import figures  # noqa: E402


def test_quoted_figures_are_current(quick_report):
    bad, n = figures.check(quick_report["out"])
    assert n >= 35, f"only {n} quoted figures found"
    assert not bad, ("stale figures (rewrite: python -m docsite.figures REPORT --update): "
                     + "; ".join(f"{b['page']}:{b['line']} {b['key']} quoted {b['quoted']} now "
                                 f"{b.get('now') or b.get('why')}" for b in bad))


def test_the_checker_fails_on_stale_unknown_and_stray_marks_and_update_fixes(quick_report, tmp_path):
    page = tmp_path / "p.md"
    good = "408.9<!--fig quick:noise_budget::read noise at the column (e-)::primary-->"
    page.write_text(f"ok {good} e-\nstale 401.9<!--fig quick:noise_budget::read noise at the column (e-)::primary--> e-\n"
                    "unknown 1.0<!--fig quick:nowhere::x::y-->\nstray <!--fig quick:checked::sizing.c_m-->\n")
    bad, n = figures.check(quick_report["out"], [page])
    assert n == 3
    assert [(b["line"], b.get("now")) for b in bad[:1]] == [(2, "408.9")]
    assert "no such figure" in bad[1]["why"] and "not right after a number" in bad[2]["why"]
    page.write_text("stale 401.9<!--fig quick:noise_budget::read noise at the column (e-)::primary--> e-, "
                    "mV 5.000<!--fig quick:checked::model_vs_spice.primary.pedestal_V*1e3-->\n")
    assert figures.update(quick_report["out"], [page]) == 2
    assert figures.check(quick_report["out"], [page])[0] == []
    assert page.read_text().startswith("stale 408.9<!--fig")


def test_prose_marks_of_blocks_records_and_derived_figures_fail_when_stale(tmp_path):
    """``block:`` (a number of a text block of the page), ``record:`` (a stored results file that says
    when and on what it was measured) and ``calc:`` (arithmetic over marks) need no run: a stale one
    names page, line, the quoted and the current value, and ``--update`` rewrites it."""
    rec = tmp_path / "rec.json"
    page = tmp_path / "p.md"
    runs = json.loads((ROOT / "benchmarks" / "results" / "main_job.json").read_text())["parts"]["report"]["current"]["spice_runs"]
    page.write_text("```text\n  C_PD,node (fF)   44.86   45.53\n```\n\n"
                    "grew 0.67<!--fig calc:{block:C_PD,node (fF)#2}-{block:C_PD,node (fF)}--> fF to "
                    "45.5<!--fig block:C_PD,node (fF)#2--> fF\n"
                    "stale 44.00<!--fig block:C_PD,node (fF)--> and -3<!--fig calc:{block:C_PD,node (fF)}*2--> fF\n"
                    f"{runs}<!--fig record:benchmarks/results/main_job.json::parts.report.current.spice_runs--> runs, "
                    f"1<!--fig record:{rec}::x-->\n"
                    "2<!--fig calc:__import__('os')--> 3<!--fig block:no such line-->\n")
    rec.write_text('{"x": 1}')
    bad, n = figures.check(None, [page], getters={})
    assert n == 8
    assert [(b["line"], b["quoted"], b.get("now")) for b in bad[:2]] == [(6, "44.00", "44.86"), (6, "-3", "90")]
    assert "no such figure" in bad[2]["why"]                       # outside the repository
    assert "not arithmetic" in bad[3]["why"] and "0 text block line(s) of the page hold 'no such line'" in bad[4]["why"]
    page.write_text(page.read_text().replace(f"1<!--fig record:{rec}::x-->", "")
                    .replace("2<!--fig calc:__import__('os')--> 3<!--fig block:no such line-->", ""))
    assert figures.update(None, [page], getters={}) == 2
    assert figures.check(None, [page], getters={})[0] == []
    assert "stale 44.86<!--fig" in page.read_text()


def test_a_record_must_say_when_and_on_what_it_was_measured(tmp_path, monkeypatch):
    monkeypatch.setattr(figures, "ROOT", tmp_path)
    (tmp_path / "r.json").write_text('{"date": "2026-11-28", "wall_s": 12.5}')
    page = tmp_path / "p.md"
    page.write_text("took 12.5<!--fig record:r.json::wall_s--> s\n")
    bad, _ = figures.check(None, [page], getters={})
    assert "date, commit" in bad[0]["why"]
    (tmp_path / "r.json").write_text('{"date": "2026-11-28", "commit": "abc1234", "wall_s": 12.5}')
    assert figures.check(None, [page], getters={})[0] == []


def test_every_page_s_block_record_and_calc_marks_are_current():
    """The marks that need no run, on every page and the README (under a second, no quick report)."""
    bad, n = figures.check(None, getters={})
    assert not bad, "; ".join(f"{b['page']}:{b['line']} {b['key']} quoted {b['quoted']} now "
                              f"{b.get('now') or b.get('why')}" for b in bad)


def test_a_block_quoting_a_dated_record_is_held_to_it(tmp_path, monkeypatch):
    """A ```text block under ``<!-- record: NAME -->`` is checked line by line against the stored run
    (``docsite/records.py``), and the page must name the record's commit; every page's record blocks
    hold (no run: the records are files)."""
    from docsite import records
    bad, n = records.check(figures.pages())
    assert not bad, "\n".join(bad)
    monkeypatch.setattr(records, "FOLDER", tmp_path)
    (tmp_path / "r.json").write_text(json.dumps({"command": "pixelkit verify X", "commit": "abc1234",
                                                 "date": "2026-11-28 23:40 UTC", "exit": 0,
                                                 "output": "spec  value\npower_chip  8.616 mW  PASS\n"}))
    page = tmp_path / "p.md"
    page.write_text("Measured at abc1234:\n\n<!-- record: r -->\n```text\npower_chip  8.62 mW  PASS\n```\n")
    assert records.check([page]) == ([], 1)
    page.write_text("Measured:\n\n<!-- record: r -->\n```text\npower_chip  8.60 mW  PASS\n```\n"
                    "<!-- record: gone -->\n```text\nx\n```\n")
    bad, n = records.check([page])
    assert n == 2 and "8.60" in bad[0] and "8.616" in bad[0] and bad[0].startswith("p.md:5")
    assert "does not name the record's commit abc1234" in bad[1] and "no record" in bad[2]


def test_unmarked_numbers_are_listed_and_marked_pages_stay_marked(tmp_path):
    """``python -m docsite.unmarked`` measures the gap: a number with a unit in a page's prose with no
    mark (not in a block, inline code, a grid condition or an estimate). The pages listed as fully
    marked gain none; ``input:`` marks are held to the design file, ``cite:`` keys to the bibliography."""
    from docsite import unmarked
    got = unmarked.gap([figures.ROOT / ("README.md" if p == "README.md" else f"docs/{p}") for p in unmarked.MARKED])
    assert not got, "unmarked numbers on a fully marked page: " + "; ".join(
        f"{page}:{line} {num}" for page, found in got.items() for line, num, _ in found)
    found = unmarked.scan("read noise 408.9 e- and 3.2<!--fig quick:x::y--> fF, ~7 %, about 2 min,\n"
                          "at ss 85 degC -10 %, `12 mV`, C_M +-10 %, a 27 x 150 array, 100,000 lines\n"
                          "```text\n1.5 mV\n```\n| x | 4.036 uV/e- |\n")
    assert [(line, num) for line, num, _ in found] == [(1, "408.9 e-"), (6, "4.036 uV/e-")]
    assert unmarked.scan("<!-- generated by a program -->\n1 uA\n") == []
    assert [n for _, n, _ in unmarked.scan("1 uA\n<!-- map: generated by x.py -->\n2 uA\n<!-- end of the map -->\n3 uA\n")] \
        == ["1 uA", "3 uA"]
    assert [n for _, n, _ in unmarked.scan("CG_jdep(2.5 V) is 6.0 uV/e- (2.5 V)\n")] == ["6.0 uV/e-", "2.5 V"]
    assert unmarked.scan("the flux from h' to 2h' of the edge\n") == []
    assert [n for _, n, _ in unmarked.scan("a 2 fC probe, 0.070<!--fig x:y--> fC\n")] == ["2 fC"]     # charges count        # a formula, not 2 hours
    page = tmp_path / "p.md"
    page.write_text("1<!--fig input:designs/dual_pixel_revA.toml::pixel.sf_bias--> uA, "
                    "2<!--fig input:designs/dual_pixel_revA.toml::pixel.sf_bias--> uA, "
                    "10<!--fig cite:Thesis2019--> mW, 3<!--fig cite:NoSuchKey2000--> mW, "
                    "5<!--fig input:the method's criterion--> %\n")
    bad, n = figures.check(None, [page], getters={})
    assert [(b["quoted"], b.get("now")) for b in bad[:1]] == [("2", "1")]
    assert len(bad) == 2 and "NoSuchKey2000" in bad[1]["why"]
    assert figures._parts('close.knobs."afe.c11".min') == ["close", "knobs", "afe.c11", "min"]
    page.write_text("10<!--fig default:afe.supply_current*1e6--> uA, 11<!--fig default:afe.supply_current*1e6--> uA\n")
    assert [(b["quoted"], b.get("now")) for b in figures.check(None, [page], getters={})[0]] == [("11", "10")]
    page.write_text("1<!--fig schema:pixel.sf_bias.plausible.1*1e3--> mA, 99<!--fig const:pixelkit.verify.figures.PLAUSIBLE.power_chip.1--> W, "
                    "1<!--fig const:os.sep--> x\n")
    bad = figures.check(None, [page], getters={})[0]
    assert [(b["quoted"], b.get("now")) for b in bad[:1]] == [("99", "100")] and "only constants of pixelkit" in bad[1]["why"]
    page.write_text("Measured at 2826076 (copies): 0.394<!--fig dated:2826076--> mV, 0.5<!--fig dated:abc1234--> mV, "
                    "1<!--fig dated:HEAD--> mV\n")
    bad = figures.check(None, [page], getters={})[0]
    assert [b["quoted"] for b in bad] == ["0.5", "1"] and "does not name the commit abc1234" in bad[0]["why"]
    assert "not a commit id" in bad[1]["why"]


def test_every_file_a_mark_reads_is_in_the_docs_clone():
    """The how-to runner checks the marks from a clone of the pages' inputs (tests/test_tutorial.py's
    CLONE_FOLDERS): a mark reading a file outside it would pass here and fail there."""
    import re
    from test_tutorial import CLONE_FOLDERS
    paths = {f[1] for p in figures.pages() for line in p.read_text().splitlines() for m in figures._outside_code(line)
             for f in re.finditer(r"(?:record|file|input):([\w./-]+)::", m.group(0))}
    outside = sorted(p for p in paths if not any(p.startswith(d + "/") for d in CLONE_FOLDERS))
    assert paths and not outside, f"marks read files the docs clone lacks (add to CLONE_FOLDERS): {outside}"


def test_every_generated_table_is_held_by_the_test_it_names(tmp_path, monkeypatch):
    """A table region ``docsite/tables.py`` writes is skipped by the unmarked counter, so each must be one
    of ``tables.TABLES``, on its page, and named by the test that holds it (which calls ``tables.hold``
    with its name); ``hold`` fails on a region that differs from what the function writes and rewrites it
    under ``PIXELKIT_DOCS_REWRITE=1``."""
    from docsite import tables
    found = {name: (p.name, test) for p in figures.pages() for name, test in tables.regions(p.read_text())}
    assert set(found) == set(tables.TABLES), (sorted(found), sorted(tables.TABLES))
    for name, (page, test, _) in tables.TABLES.items():
        assert found[name] == (page, test), (name, found[name])
        source = (ROOT / test).read_text()
        assert "tables.hold(" in source and f'"{name}"' in source, f"{test} does not hold table {name}"
    monkeypatch.setattr(tables, "ROOT", tmp_path)
    (tmp_path / "docs").mkdir()
    page = tmp_path / "docs" / "p.md"
    monkeypatch.setitem(tables.TABLES, "t", ("p.md", "tests/x.py", lambda data: f"| x |\n|---|\n| {data:.2f} |"))
    page.write_text("a\n<!-- table t: generated by docsite/tables.py from tests/x.py (rewrite) -->\n| x |\n|---|\n"
                    "| 1.00 |\n<!-- end of table t -->\nb\n")
    assert tables.hold("t", 1.0) == ""
    bad = tables.hold("t", 1.5)
    assert "p.md:3: table 't'" in bad and "page: | 1.00 |" in bad and "kit:  | 1.50 |" in bad
    monkeypatch.setenv("PIXELKIT_DOCS_REWRITE", "1")
    assert tables.hold("t", 1.5) == "" and "| 1.50 |\n<!-- end of table t -->\nb" in page.read_text()
    from docsite import unmarked
    assert unmarked.scan(page.read_text().replace("| 1.50 |", "| 1.50 fF |")) == []


def test_tables_made_from_records_are_the_records():
    """A generated table whose data is stored records (``tables.RECORD_TABLES``: the light map's verdict,
    docs/post-layout.md) is what the records say; no run (a record is a dated run, its commit in the table)."""
    from docsite import tables
    assert set(tables.RECORD_TABLES) == {"lightmap"}
    for name in ("lightmap",):
        bad = tables.hold(name, tables.record_data(name))
        assert not bad, bad
def test_a_tests_own_source_is_held_and_rewritten(tmp_path, monkeypatch):
    """``figures.hold``: the page check of a test that computes its source's figures (``sf:``, ``wdr:``, ``gss:``,
    ``lim:``) names a stale figure's page and line, leaves other sources' marks alone, and rewrites under
    ``PIXELKIT_DOCS_REWRITE``."""
    page = tmp_path / "p.md"
    page.write_text("gain +3.05<!--fig xx:gain.4uA.1--> %, band 2.5<!--fig xx:band.0*-1--> %, other 1.0<!--fig afen:a-->\n")
    data = {"gain": {"4uA": [0.0, 3.049]}, "band": [-2.46]}
    monkeypatch.delenv("PIXELKIT_DOCS_REWRITE", raising=False)
    assert figures.hold([page], "xx", data) == []
    data["gain"]["4uA"][1] = 3.12
    assert figures.hold([page], "xx", data) == ["p.md:1: xx:gain.4uA.1: quoted +3.05, now +3.12"]
    monkeypatch.setenv("PIXELKIT_DOCS_REWRITE", "1")
    assert figures.hold([page], "xx", data) == [] and page.read_text().startswith("gain +3.12<!--fig")


#: the pages each test holding a source of its own (``figures.OTHER_SOURCES``) checks: the general check skips
#: those marks (``_elsewhere``), so a mark of one on a page its test does not read would be checked by nobody
HELD_ON = {"p4t": "*", "pl": ("post-layout.md",), "xs": ("post-layout.md",), "stk": ("post-layout.md",),
           "afen": ("noise-camera.md",), "afeg": ("pixel-model.md", "verify.md"), "stl": ("verify.md",),
           "nzf": ("noise-camera.md", "timing-and-settling.md"), "sf": ("source-follower.md",),
           "wdr": ("dark-current.md",), "gss": ("gap-diagnosis.md",), "lim": ("revisions.md",),
           "ppw": ("pixel4t.md",), "ppd": ("pixel4t.md",), "ppv": ("pixel4t.md",)}


def test_every_mark_of_a_source_a_test_holds_stands_on_a_page_that_test_reads():
    """A ``sf:`` (``p4t:``, ...) mark is checked only by its test, on the pages that test names (``HELD_ON``;
    ``p4t:`` on every page with a ``<!--fig p4t:`` mark, tests/test_pixel4t.py); one on another page, or inside a
    calc on a page without such a mark, would pass unchecked. A new source names its pages here."""
    assert set(HELD_ON) == set(figures.OTHER_SOURCES)
    stray = []
    for page in figures.pages():
        text = page.read_text()
        used = {m["src"] for m in figures.MARK.finditer(text)} | {s for s, _ in figures.REF.findall(text)}
        for src in used & set(HELD_ON):
            ok = "<!--fig p4t:" in text if HELD_ON[src] == "*" else page.name in HELD_ON[src]
            if not ok:
                stray.append(f"{page.name}: {src}:")
    assert not stray, stray
