"""docs/validation.md stays true: every command of ``pixelkit`` has a row naming tests that
exist and the kind of independent reference they rest on.

Reference of this test: the command group itself (``pixelkit.cli``: every command registered)
and the test files parsed as Python (``ast``), not the table's own claims.
"""
import ast
import re
from pathlib import Path

from conftest import ROOT
from figure_references import KINDS   # one list of the kinds of reference

TABLE = ROOT / "docs" / "validation.md"
TEST_REF = re.compile(r"`(tests/[\w/]+\.py)::(test_\w+)`")


def commands() -> set[str]:
    from pixelkit.cli import register_all
    from pixelkit.cli.common import main
    register_all()
    return set(main.commands)


def rows(text: str) -> dict[str, list[str]]:
    """{command: cells} of the table's rows (``| `command` | ... |``)."""
    out = {}
    for line in text.splitlines():
        m = re.match(r"\|\s*`([\w-]+)`\s*\|", line)
        if m:
            out[m.group(1)] = [c.strip() for c in line.strip().strip("|").split("|")]
    return out


def _tests_in(path: Path) -> set[str]:
    tree = ast.parse(path.read_text())
    return {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))}


def problems(text: str, root: Path, names: set[str]) -> list[str]:
    """Everything wrong with the table ``text`` for the commands ``names`` (tests under ``root``)."""
    bad = []
    table = rows(text)
    bad += [f"{c}: no row" for c in sorted(names - set(table))]
    bad += [f"{c}: a row for a command pixelkit does not have" for c in sorted(set(table) - names)]
    for cmd, cells in table.items():
        if len(cells) != 5:
            bad.append(f"{cmd}: {len(cells)} cells, want 5 (command, figures, tests, reference, kind)")
            continue
        refs = TEST_REF.findall(cells[2])
        if not [t for _, t in refs if not t.endswith("_unchanged")]:
            bad.append(f"{cmd}: names no test that checks against a reference (a change detector is not one)")
        for file, test in refs:
            path = root / file
            if not path.is_file():
                bad.append(f"{cmd}: {file} does not exist")
            elif test not in _tests_in(path):
                bad.append(f"{cmd}: {file} has no {test}")
        kinds = [k.strip() for k in cells[4].split(",") if k.strip()]
        if not kinds:
            bad.append(f"{cmd}: no kind of reference")
        bad += [f"{cmd}: '{k}' is not a kind of reference ({', '.join(KINDS)})" for k in kinds if k not in KINDS]
        if not cells[3]:
            bad.append(f"{cmd}: the reference is not said")
    return bad


def test_every_command_has_a_row_naming_existing_tests_and_a_reference():
    bad = problems(TABLE.read_text(), ROOT, commands())
    assert not bad, "\n".join(bad)


def test_the_check_catches_a_missing_row_a_missing_test_and_a_bad_kind(tmp_path):
    """The check can fail: a planted table and test file with one offence of each kind."""
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "test_a.py").write_text("def test_real():\n    pass\n")
    ok = "| `a` | x | `tests/test_a.py::test_real` | y | derivation |"
    planted = "\n".join([
        ok,
        "| `b` | x | `tests/test_a.py::test_gone` | y | derivation |",
        "| `c` | x | `tests/test_b.py::test_real` | y | derivation |",
        "| `d` | x | `tests/test_a.py::test_real` | y | gut feeling |",
        "| `e` | x | `tests/test_a.py::test_golden_unchanged` | y | derivation |",
        "| `f` | x | `tests/test_a.py::test_real` | y |",
        "| `zz` | x | `tests/test_a.py::test_real` | y | derivation |",
    ])
    bad = problems(planted, tmp_path, {"a", "b", "c", "d", "e", "f", "g"})
    assert not problems(ok, tmp_path, {"a"})
    for needle in ("g: no row", "b: tests/test_a.py has no test_gone", "c: tests/test_b.py does not exist",
                   "d: 'gut feeling' is not a kind", "e: names no test that checks", "f: 4 cells",
                   "zz: a row for a command pixelkit does not have", "e: tests/test_a.py has no test_golden"):
        assert any(b.startswith(needle) for b in bad), (needle, bad)
