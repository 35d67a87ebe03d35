"""``pixelkit gap surrogate`` run as a command, and the surrogate it writes held against fresh SPICE.

The command runs in a subprocess under a thinned build plan (``gap_thin_plan``: 12 grid charges, one
temperature, one light current, three sites at one amplitude; ~30 decks instead of ~350), so the
whole path the user runs - design loaded, both build rounds in ngspice, tables fitted, the surrogate
stored with its decks' key, the JSON answer - is exercised within a minute.

Independent path: the dual-pixel bench a user simulates (``chains.standard``: one primary and three
secondary chains with their AFEs), run fresh by ngspice at charges halfway between grid charges that
neither the tables nor the surrogate's own validation decks used; the written surrogate, read back from
the file, must predict both probes (column level at the signal sample, AFE output) there within its
stated error plus ``store.CHECK_TOL_V`` - the rule ``store.check`` applies to a shipped surrogate's plain
deck. The shipped full-plan surrogates are checked in ``test_gap_surrogate.py``.
"""
import json
import subprocess
import sys

import numpy as np
import pytest

from conftest import REF, ROOT

THIN = ROOT / "tests" / "gap_thin_plan.py"
#: check decks: the grid intervals (each deck's four chains at the midpoint of one interval) the build used for
#: nothing (``gap_thin_plan``'s validation intervals are 3, 7 and 9): a low one, the middle of the range and the top one
#: (the column reaching its rail, where a spline between charges bends most). One interval per deck, as the
#: surrogate's validation decks have it: the bench's levels move with what its other chains do (measured: the
#: primary at interval 5 read 2.3 mV higher with its secondaries at intervals 1, 5 and 10 than with all at 5,
#: and 0.1 mV with all at 1 or at 10; with the decks' largest time step divided by 8 the two agree to 0.05 mV: the
#: integration error of the bench at the kit's step), beyond the surrogate's tolerance and not this command's doing.
CHECK = (1, 5, 10)


def _run(*args, timeout=900):
    p = subprocess.run([sys.executable, str(THIN), *map(str, args)], capture_output=True, text=True, cwd=ROOT,
                       timeout=timeout)
    return p.returncode, p.stdout, p.stderr


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("surrogate") / "revA_thin.json"
    code, stdout, err = _run("gap", "surrogate", REF, "--out", out, "--json")
    assert code == 0, err[-2000:]
    return json.loads(stdout), out


@pytest.fixture
def thin_plan(monkeypatch):
    import gap_thin_plan
    gap_thin_plan.thin(monkeypatch.setattr)


def test_the_command_writes_a_surrogate_keyed_to_its_plan(built, ref_design, thin_plan):
    """The answer names the file and the error stated in it; the file reads back under the plan that made it
    (its key is the key of those decks)."""
    from pixelkit.gap import store
    answer, out = built
    assert answer["out"] == str(out)
    doc = json.loads(out.read_text())
    assert doc["design"] == ref_design.name and doc["nominal"]["error"] == answer["error_V"]
    nom = store.read(ref_design, out)
    assert nom is not None
    assert len(nom.q_grid["primary"]) == 12 and nom.error["n_validation"] == 6


def test_a_thinned_surrogate_is_not_taken_for_the_designs_own(built, ref_design):
    """Under the kit's full plan the same file's key is another plan's: ``store.read`` refuses it, so
    ``gap diagnose`` would never use these coarser tables in place of the design's surrogate."""
    from pixelkit.gap import store
    assert store.read(ref_design, built[1]) is None


def test_the_written_surrogate_predicts_fresh_spice_between_its_charges(built, ref_design, thin_plan):
    from pixelkit.circuits.testbench import timings
    from pixelkit.gap import store
    from pixelkit.gap.chains import standard
    from pixelkit.gap.nominal import ARRAYS, predict
    from pixelkit.measure.pixel import levels
    from pixelkit.spice import simulate_many
    d = ref_design
    nom = store.read(d, built[1])
    e = nom.error
    assert max(e["pixel_max_V"], e["afe_max_V"]) < 2e-3, e   # 12 charges: ~0.9 mV measured (full plan 0.2 mV)
    mid = {a: (nom.q_grid[a][1:] + nom.q_grid[a][:-1]) / 2 for a in ARRAYS}
    nets, picks = [], []
    for k in CHECK:
        net, cs = standard(d, mid["primary"][k], mid["secondary"][k], f"gapcmdcheck{k}")
        nets.append(net)
        picks.append([(c, k) for c in cs])
    tm = timings(d, d.experiment.t_window)
    tol = np.array([e["pixel_max_V"], e["afe_max_V"]]) + store.CHECK_TOL_V
    seen = []
    for r, chain_ks in zip(simulate_many(nets), picks):
        for c, k in chain_ks:
            q = mid[c.array][k]
            got = np.array([levels(r, c.col, tm[c.array])[0], float(r.at(c.out, tm[c.array].t_reset_level(0)))])
            X = {"arr": np.full(2, ARRAYS.index(c.array)), "q": np.array([q, q]), "afe": np.array([False, True]),
                 "dT": np.zeros(2)}
            dev = np.abs(got - predict(nom, X))
            assert np.all(dev <= tol), (c.array, k, dev, tol)
            seen.append(got)
    # the agreement is not a flat line's: the levels the check decks span are hundreds of times the tolerance
    assert np.ptp(np.array(seen)[:, 0]) > 0.3 and np.ptp(np.array(seen)[:, 1]) > 0.3, seen


@pytest.mark.parametrize("args, field", [
    (("designs/pixel4t_gf180.toml",), ("family", "pixel4t")),
    (("designs/no_such_design.toml",), ("design", "designs/no_such_design.toml")),
    ((REF, "--out", ROOT / "README.md" / "revA.json"), None),
], ids=["another-family", "no-file", "out-under-a-file"])
def test_bad_input_is_a_usage_error_before_any_simulation(tmp_path, args, field):
    """A design the gap module cannot build for (another family, no file) or an output under a regular file:
    exit 2 with the field named, no traceback, and nothing simulated (the command's own SPICE cache stays
    empty: the answer comes before the build's first deck)."""
    import os
    cache = tmp_path / "cache"
    p = subprocess.run([sys.executable, "-m", "pixelkit", "gap", "surrogate", *map(str, args), "--json"],
                       capture_output=True, text=True, cwd=ROOT, timeout=300,
                       env=dict(os.environ, PIXELKIT_CACHE=str(cache)))
    assert p.returncode == 2, p.stderr
    doc = json.loads(p.stdout)
    assert doc["exit_status"] == 2 and "Traceback" not in p.stderr
    if field:
        assert (doc["field"], doc["value"]) == field
    else:
        assert "README.md" in doc["error"] and "not a folder" in doc["error"]
    assert not any(f.is_file() for f in cache.rglob("*")), sorted(cache.rglob("*"))
