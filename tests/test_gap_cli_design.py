"""Every ``pixelkit gap`` command works on the design it is given: none falls back to a fixed design, and data
made of another design (the kit's committed SPICE cases of the thesis read [Thesis2019], the OOD sets of the reference) are
refused by name, never diagnosed against the given design. Cheap: the refusals come before any surrogate or
SPICE run (~3 s each); the ``silicon`` folder test runs the command in-process with its SPICE replaced.
"""
import json
from pathlib import Path

from conftest import ROOT

REVA = ROOT / "designs" / "dual_pixel_revA.toml"
REVB = ROOT / "designs" / "dual_pixel_revB.toml"


def test_selftest_refuses_the_thesis_reads_cases_for_another_design(cli):
    """`gap selftest revA --kind spice`: the kit's committed SPICE cases are of the thesis read, so for revA the
    command says so and names --spice-cases (exit 2) instead of diagnosing the thesis read's data against revA."""
    code, out, err = cli("gap", "selftest", REVA, "--kind", "spice", "--json")
    assert code == 2, err
    e = json.loads(out)
    assert e["field"] == "--spice-cases" and "dual_pixel_revA_thesis_read" in e["error"] and "Traceback" not in err


def test_selftest_ood_refuses_a_design_its_sets_are_not_of(cli):
    """`gap selftest revB --ood dev`: the OOD sets are lab data of revA; given revB it refuses (exit 2) where it
    used to diagnose revA whatever DESIGN said."""
    code, out, err = cli("gap", "selftest", REVB, "--ood", "dev", "--json")
    assert code == 2, err
    e = json.loads(out)
    assert e["field"] == "DESIGN" and "dual_pixel_revA" in e["error"]


def test_surrogate_needs_its_design(cli):
    """`gap surrogate` builds the surrogate of the design given; without one it is a usage error (it used to
    build the thesis read's)."""
    code, out, err = cli("gap", "surrogate")
    assert code == 2 and "DESIGN" in err


def test_silicon_writes_another_designs_cases_beside_its_reports(tmp_path, monkeypatch):
    """`gap silicon revA` (no --out) writes reports/dual_pixel_revA/silicon_cases, never over the kit's committed
    cases of the thesis read; no DESIGN still means the thesis read and the kit's folder. The SPICE cases and the
    surrogate are replaced by recorders (the folder choice is what is tested)."""
    from pixelkit.cli import entry
    from pixelkit.gap import silicon, store
    seen = []
    monkeypatch.setattr(store, "load_nominal", lambda d, backend="batch": None)
    monkeypatch.setattr(silicon, "write_cases", lambda d, nom, folder, plan, **kw:
                        seen.append((d.name, Path(folder))) or {"n_cases": 0, "folder": str(folder)})
    monkeypatch.setenv("PIXELKIT_REPORTS", str(tmp_path / "reports"))
    for args in ([str(REVA)], []):
        entry(["gap", "silicon", *args, "--json"])
    assert seen[0] == ("dual_pixel_revA", tmp_path / "reports" / "dual_pixel_revA" / "silicon_cases")
    assert seen[1] == ("dual_pixel_revA_thesis_read", silicon.CASES_DIR)
