"""Every number a docs page marks as quoted from the kit (``docsite/figures.py``) is the kit's
current output at the digits quoted: the session's quick report of the reference design is the
reference (the kit's own output, which is what the page claims to quote). The checker is shown to
fail on a planted stale figure, on a key that names nothing and on a marker not after a number,
and ``--update`` to rewrite a stale figure with the same digits."""
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
