"""The diagnosis on out-of-distribution virtual silicon: effects made by mechanisms the surrogate never tabulates.

Independent path: ``tests/data/gap_ood`` holds lab data of the reference design made by ngspice with each
effect inserted by its physical mechanism (``pixelkit/gap/ood.py``: the source follower's W and L, the load's
length, the AFE's capacitors as the layout leaves them, junction leakage by generation and diffusion with
silicon's band gap, a switched voltage-dependent leak on FD, wider channel charge, the GF180 layout's open
junctions...), every deck at its operating point's die temperature, under one irradiance for both arrays, with
an uncalibrated bench's gain, offset and noise. None of the surrogate's site elements, none of the effect
library's functions enter. The development set (``dev``) is what the diagnosis was looked at on; the held-out
set (``heldout``, other seeds, ``ood.plan_set``) is scored against the issue's targets and never tuned on
(the scores: the two slow tests, docs/gap-diagnosis.md). Cost of the default tests: the reference surrogate's
check (4 decks) and one case (10 decks), ~30 s on 2 cores.
"""
import numpy as np
import pytest

from pixelkit.gap import ood, silicon


@pytest.fixture(scope="module")
def reference_nominal(ref_design):
    from pixelkit.gap.store import load_nominal
    return load_nominal(ref_design)


@pytest.mark.parametrize("name", ["dev", "heldout", "heldout2"])
def test_sets_are_complete_and_their_seeds_their_own(name):
    """Every kind in each set, effect-free chips and outside effects included, each set exactly its planned
    seeds (so no two share one). (``heldout2`` was generated over three sessions: its first 27 cases at the
    dual-pixel bench's 20 ns step, the rest at one clock edge, all from the same shipped nominal.)"""
    _, truths = silicon.load_cases(ood.OOD_DIR / name)
    assert {t["circuit"] for t in truths.values()} == set(ood.KINDS)
    assert sum(t["effect"] == "out_of_library" for t in truths.values()) >= 8
    assert sum(t["effect"] == "none" for t in truths.values()) >= 6
    assert {t["seed"]: t["circuit"] for t in truths.values()} == {s: k for k, s in ood.plan_set(name)}
    others = {s for n in ood.SETS if n != name for _, s in ood.plan_set(n)}
    assert not {s for _, s in ood.plan_set(name)} & others


def test_generator_never_uses_the_surrogates_edits(ref_design, reference_nominal):
    """Every kind's deck holds none of the elements the surrogate's site tables are measured with (``responses``:
    Csite / Isite / Rsite ...) and no vm current source (``circuit_edits.vm_current``)."""
    g = np.random.default_rng(3)
    for kind, k in ood.KINDS.items():
        p = k.draw(g, ref_design)
        ops = ood.operating_points(ref_design, reference_nominal, g, k.campaign)
        colp = ood.column_draws(ref_design, g, kind, p, ops)
        pattern = ((("vm", "psd", 1.0),), 1e-12) if kind == "layout_light" else ()
        op = next(o for o in ops if o["J"] > 0)
        net, _ = ood.deck(ref_design, reference_nominal, op, kind, p, colp, pattern, f"t{kind}")
        text = net.text().lower()
        assert "site" not in text and "\nilt " not in text, kind
        assert f".temp {op['temp']:g}" in text      # the devices at the die's temperature


def test_one_case_is_reproduced_by_spice(ref_design, reference_nominal, monkeypatch):
    """The committed rows are ngspice's: one case re-simulated from its seed (10 decks) gives them again, at the
    dual-pixel bench's own time step the set was made with (before the gap's decks stepped one clock edge,
    ``chains.edge_resolved``; at one edge this case's rows move by up to 0.23 mV: the integration floor)."""
    from pixelkit.gap import chains
    monkeypatch.setattr(chains, "edge_resolved", lambda net, design: net)
    cases, truths = silicon.load_cases(ood.OOD_DIR / "dev")
    cid = next(c for c, t in truths.items() if t["circuit"] == "fd_junction")
    rows, truth = ood.simulate_case(ref_design, reference_nominal, "fd_junction", truths[cid]["seed"])
    from pixelkit.report.diff import _flat   # nested tables to dotted keys, as the revision diff reads them
    assert _flat(truth["params"]) == pytest.approx(_flat(truths[cid]["params"]))
    got = np.array([r["v_V"] for r in rows])
    want = np.array([float(r["v_V"]) for r in cases[cid]])
    assert np.max(np.abs(got - want)) < 0.2e-3


@pytest.mark.slow
def test_development_set_score_holds(ref_design, reference_nominal):
    """The development set's score as measured when it landed (62 cases, ~4 min of CPU: slow):
    top-1 46 / 48, explained when right 37 / 46, every outside effect "not explained", none on every
    effect-free chip. A guard against regressions on data the diagnosis was looked at on; the issue's targets
    (90 % / 90 %) are for the held-out set (docs/gap-diagnosis.md)."""
    r = ood.run_set(ref_design, reference_nominal, "dev")
    assert r["top1_accuracy"] >= 46 / 48 - 1e-9, r["per_effect_top1"]
    assert r["explained_when_right"] >= 37 / 46 - 1e-9, r["per_kind_explained"]
    assert r["not_explained_on_out_of_library"] == 1.0 and r["none_on_clean"] == 1.0


@pytest.mark.slow
def test_heldout_set_score_as_measured(ref_design, reference_nominal):
    """The held-out set, blind (62 cases, ~6 min at a load of 4-9: slow), as measured when it landed: top-1 43 / 48,
    explained when right 36 / 43, 7 of 8 outside effects "not explained", none on every effect-free chip.
    Issue 46's targets (top-1 and explained-when-right >= 90 %, no outside effect explained) are NOT met yet
    (docs/gap-diagnosis.md lists the misses); this guards what is reached and fails if it drops."""
    r = ood.run_set(ref_design, reference_nominal, "heldout")
    assert r["top1_accuracy"] >= 43 / 48 - 1e-9, r["per_effect_top1"]
    assert r["explained_when_right"] >= 36 / 43 - 1e-9, r["per_kind_explained"]
    assert r["not_explained_on_out_of_library"] >= 7 / 8 - 1e-9 and r["none_on_clean"] == 1.0


@pytest.mark.slow
def test_second_heldout_set_score_as_measured(ref_design, reference_nominal):
    """The second held-out set (62 cases, seeds 90000-90061, drawn after the first was seen; slow: 20 min of two
    processes at a load of 14-26). Scored blind once on 53a590a (f4b7be8 on main): top-1 44 / 48, explained when
    right 40 / 44, every outside effect "not explained" (8 / 8, each with a visible gap), none on the six effect-free
    chips (docs/gap-diagnosis.md; its first 51 cases on a2b0b0a: 36 / 40, 30 / 36). Held at issue 46's targets:
    top-1 and explained when right >= 90 %, no outside effect explained."""
    r = ood.run_set(ref_design, reference_nominal, "heldout2")
    assert r["n_effect_cases"] == 48
    assert r["top1_accuracy"] >= 0.9, r["per_effect_top1"]
    assert r["explained_when_right"] >= 0.9, r["per_kind_explained"]
    assert r["not_explained_on_out_of_library"] == 1.0 and r["none_on_clean"] == 1.0


def test_a_column_afe_pattern_is_named_with_its_spatial_law(ref_design, reference_nominal):
    """A per-column AFE gain pattern along each array (C11 on an oxide gradient: a slope of its own per array)
    plus each column's mismatch is named ``column_afe``, explained, and the fitted slopes are the drawn ones
    (within 30 %). The data come from the surrogate's own terms (``nominal.predict``): this checks the fit's
    arithmetic and that the law is identifiable beside the per-column terms and the set-up, not the physics (the
    OOD sets' ``afe_columns`` cases do that, with SPICE). ~5 s."""
    from pixelkit.gap.diagnose import diagnose
    from pixelkit.gap.nominal import features, predict
    from pixelkit.gap.selftest import campaign
    g = np.random.default_rng(7)
    tab = campaign(ref_design, reference_nominal, g, vary_setup=False)
    X = features(tab, reference_nominal, ref_design)
    slope = np.where(X["arr"] == 0, 0.006, -0.004)
    keys = X["arr"] * 1000 + X["col"].astype(int)
    own = {k: g.normal(0, 0.001) for k in np.unique(keys)}
    c11 = slope * 2 * X["col_pos"] + np.array([own[k] for k in keys])
    sd = tab.num("v_std_V") / np.sqrt(tab.num("n_avg"))
    tab.columns["v_V"] = predict(reference_nominal, X, {"c11": c11}) + g.normal(0, 1, sd.size) * sd
    d = diagnose(ref_design, tab, reference_nominal, candidates=("column_afe", "afe_gain", "column_pixel"),
                 setup=ood.stated_setup())
    assert d["best"] == "column_afe" and d["explained"], d["verdict"]
    got = next(r for r in d["ranking"] if r["effect"] == "column_afe")["params"]
    assert got["c11_rel_slope[primary]"] == pytest.approx(0.006, rel=0.3)
    assert got["c11_rel_slope[secondary]"] == pytest.approx(-0.004, rel=0.3)
