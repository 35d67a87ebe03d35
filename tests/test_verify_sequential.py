"""Sequential Monte Carlo (``verify``'s default): it stops once every yield is decided against
``[verify] min_yield`` and must give the verdict and an interval holding the yield of the full run.

Independent paths: Bernoulli sequences drawn by numpy with a known yield (the rule's error rate
against its stated confidence, counted directly), and the full run of the same samples
(``mc_full``: the draws of sample i depend on (seed, i) only, so the early stop is a prefix of it).
"""
import copy
import tomllib

import numpy as np
import pytest

from conftest import REF
from pixelkit.design import load_design
from pixelkit.schema import to_toml
from pixelkit.verify import measure
from pixelkit.verify.run import verify
from pixelkit.verify.yields import clopper_pearson, decided, looks, stop_confidence

NOMINAL = dict(corners=("tt",), temperatures=(300.15,), supplies=(0.0,))


def _sequential(passes: np.ndarray, min_yield: float, conf: float) -> tuple[int, str | None]:
    """(samples used, verdict) of the rule on one sequence of pass (1) / fail (0) draws."""
    n_max = passes.size
    for n in looks(n_max):
        verdict = decided(int(passes[:n].sum()), n, min_yield, conf, n_max)
        if verdict:
            return n, verdict
    return n_max, None


def test_looks_and_stopping_level():
    assert looks(200) == list(range(20, 201, 20))
    assert looks(45) == [20, 40, 45] and looks(7) == [7] and looks(0) == []
    assert stop_confidence(0.95, 200) == pytest.approx(0.995)
    # all-pass runs: decided above 90 % once (0.0025)^(1/n) >= 0.9, i.e. from 57 samples: the look at 60
    assert _sequential(np.ones(200), 0.9, 0.95) == (60, "above")
    assert _sequential(np.zeros(200), 0.9, 0.95) == (20, "below")
    # 0 % yield with min_yield 0: nothing to decide (a yield cannot lie below 0)
    assert decided(0, 20, 0.0, 0.95, 200) == "above"


@pytest.mark.parametrize("p", [0.80, 0.86, 0.90, 0.94, 0.99])
def test_rule_errs_no_more_than_its_confidence_on_bernoulli_sequences(p):
    """20000 sequences of 200 draws at yield p against min_yield 90 %: a stop on the wrong side of
    min_yield happens at most (1 - confidence) / 2 of the time (plus the count's own 3-sigma), and
    where the full run's own interval decides, the early verdict agrees with it."""
    rng = np.random.default_rng(1)
    conf, min_yield, trials, n_max = 0.95, 0.9, 20000, 200
    # the rule's verdict for every (look, passes so far), then all sequences at once
    table = {n: [decided(k, n, min_yield, conf, n_max) for k in range(n + 1)] for n in looks(n_max)}
    passes = np.cumsum(rng.random((trials, n_max)) < p, axis=1)
    verdict = np.full(trials, None, dtype=object)
    used = np.full(trials, n_max)
    for n in looks(n_max):
        open_ = verdict == None  # noqa: E711 (element-wise)
        v = np.array([table[n][k] for k in passes[:, n - 1]], dtype=object)
        stop = open_ & (v != None)  # noqa: E711
        verdict[stop], used[stop] = v[stop], n
    wrong = int(np.sum(verdict == ("above" if p < min_yield else "below")))
    bound = (1 - conf) / 2 * trials
    assert wrong <= bound + 3 * np.sqrt(bound), (p, wrong)
    full = np.array([table[n_max][k] for k in passes[:, -1]], dtype=object)
    both = (full != None) & (verdict != None)  # noqa: E711
    if both.any():
        assert np.mean(full[both] == verdict[both]) > 0.99, p
    if p == 0.99:   # far above min_yield: decided well before the full count
        assert used.mean() < 120, used.mean()


def _design(tmp_path, spec: dict, min_yield: float):
    raw = copy.deepcopy(tomllib.loads(REF.read_text()))
    raw["spec"] = {"afe_gain_error": spec}
    raw["verify"] = {**raw.get("verify", {}), "mc": 40, "seed": 3, "min_yield": min_yield}
    p = tmp_path / "d.toml"
    p.write_text(to_toml(raw))
    return load_design(p)


def _yield(r):
    return r["rows"][0]["status"], r["rows"][0]["yield"]


@pytest.mark.parametrize("case", ["far above", "far below", "near"])
def test_sequential_gives_the_full_runs_verdict_far_from_and_near_min_yield(tmp_path, case):
    """The AFE gain error over 40 samples (seed 3, the samples of test_verify's median test): far
    above min_yield (limit 1 %, every sample passes), far below (limit under the mismatch-free
    value, ~none pass) and near it (limit at the mismatch-free value: ~50 % against min_yield 50 %).
    Far: it stops at the first look (20 samples) with the full run's verdict and an interval
    holding the full run's yield; near: it cannot decide and runs the full count, same table."""
    base = _design(tmp_path, {"max": "1 %"}, 0.5)
    nominal = measure.figures({"afe": measure.afe(base)})["afe_gain_error"]
    limit = {"far above": "1 %", "far below": f"{100 * nominal * 0.5} %", "near": f"{100 * nominal} %"}[case]
    d = _design(tmp_path, {"max": limit}, 0.5)
    full = verify(d, mc_full=True, **NOMINAL)
    fast = verify(d, **NOMINAL)
    (s_full, y_full), (s_fast, y_fast) = _yield(full), _yield(fast)
    assert y_full["samples"] == 40 and full["mc"]["stop"] == "full count"
    assert s_fast == s_full
    lo, hi = y_fast["interval"]
    assert lo <= y_full["yield"] <= hi
    assert fast["mc_values"]["afe_gain_error"] == full["mc_values"]["afe_gain_error"][:y_fast["samples"]]
    if case == "near":
        assert 0.3 < y_full["yield"] < 0.7
        assert y_fast == y_full and "not every yield decided" in fast["mc"]["stop"]
    else:
        assert y_fast["samples"] == 20 and "every yield decided" in fast["mc"]["stop"]
        assert s_full == ("pass" if case == "far above" else "fail")


@pytest.mark.slow
def test_reference_design_fast_path_against_the_full_count(ref_design):
    """(slow: ~50 s of CPU, 330 decks; 10 min of wall at a load of 16) The reference design's own
    specs at its nominal condition, Monte Carlo of 40 (of its 200): the default (sequential: min_yield 0, so 20 samples) against --mc-full. Every
    spec's value, worst condition, margin and status are the same (the Monte Carlo does not enter
    them: the checked figures of the report's summary.json are these values); each yield keeps
    its verdict and its interval holds the full run's yield; the 20 are the full run's first 20."""
    from dataclasses import replace
    d = replace(ref_design, verify=replace(ref_design.verify, mc=40))
    full = verify(d, mc_full=True, **NOMINAL)
    fast = verify(d, **NOMINAL)
    assert fast["mc"]["samples"] == 20 and full["mc"]["samples"] == 40
    for a, b in zip(fast["rows"], full["rows"]):
        assert {k: v for k, v in a.items() if k != "yield"} == {k: v for k, v in b.items() if k != "yield"}
        if b["yield"] is None:
            assert a["yield"] is None
            continue
        lo, hi = a["yield"]["interval"]
        assert lo <= b["yield"]["yield"] <= hi, (a["spec"], a["yield"], b["yield"])
    for name, values in fast["mc_values"].items():
        assert values == full["mc_values"][name][:20]
    assert fast["power"] == full["power"] and fast["conditions"] == full["conditions"]
