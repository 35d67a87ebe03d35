"""Sign-off decks the figures do not need are not run (issue 41), without SPICE.

- The N secondary columns of an array bench are N independent copies on the schematic with nominal
  devices (each column's own bias generator; only ideal sources shared), so ``verify.copies.one_column``
  simulates one of them for settling and power: checked on the deck's connectivity (a node shared by two
  columns that no ideal voltage source holds would couple them, and the test fails), and refused where
  the copies differ (extracted parasitics, a Monte Carlo draw).
- The storage group runs only the kinds whose ``storage_light`` figure is asked
  (``verify.measure.asking``), every kind when nothing says (``measure_at``, ``pixelkit close``).
"""
from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

import pytest

from pixelkit.design import load_design
from pixelkit.verify import copies, measure, mismatch, power

REV_B = Path(__file__).resolve().parents[1] / "designs" / "dual_pixel_revB.toml"


def _columns_apart(net, n: int) -> set:
    """The connected parts (by node) the secondary column lines fall in, nodes held by an ideal
    voltage source to ground (and ground) cut."""
    held = {"0"} | {e.nodes[0] for e in net.elements if e.name[0] in "Vv" and e.nodes[1] == "0"}
    parent: dict = {}

    def root(x):
        while parent.setdefault(x, x) != x:
            x = parent[x]
        return x
    for e in net.elements:
        free = [x for x in e.nodes if x not in held and not str(x).startswith(("pix5t", "scafe"))]
        for a, b in zip(free, free[1:]):
            parent[root(a)] = root(b)
    return {root(f"col_s_{j}") for j in range(n)}


@pytest.mark.parametrize("which", ["ref", "revB"])
def test_secondary_columns_of_a_bench_are_independent_copies(ref_design, which):
    d = ref_design if which == "ref" else load_design(REV_B)
    n = d.secondary_per_pixel
    net = power._bench(d, "secondary")
    assert len(_columns_apart(net, n)) == n            # no node couples two columns
    one = copies.one_column(d)
    assert one.secondary_per_pixel == 1
    single = power._bench(one, "secondary")
    lines = set(net.text().splitlines())
    for k in range(n):      # every line of the one-column deck is in the N-column deck, renamed to column k
        mine = re.sub(r"(Xs_\d+_)0(?!\d)", rf"\g<1>{k}", re.sub(r"col_s_0(?!\d)", f"col_s_{k}", single.text()))
        assert set(mine.splitlines()) <= lines, k
    assert len(lines) > len(set(single.text().splitlines()))
    assert power._bench(one, "primary").text() == power._bench(d, "primary").text()


def test_one_column_refused_where_the_copies_differ(ref_design):
    assert copies.one_column(ref_design, draw=mismatch.Draw(1, 0, "library")) is None
    assert copies.one_column(replace(ref_design, post_layout=object())) is None
    assert copies.one_column(replace(ref_design, secondary_per_pixel=1)) is None


def test_storage_runs_the_asked_kinds_only(ref_design, monkeypatch):
    titles = []

    def fake(nets, design, draw, backend):
        titles.extend(x.title for x in nets)
        raise _Stop
    monkeypatch.setattr(measure, "_run", fake)
    with pytest.raises(_Stop):
        measure.storage(ref_design)
    assert titles == ["vfy_sto_dark_primary", "vfy_sto_lit_primary"]     # nothing said: every kind, primary first
    titles.clear()
    with measure.asking(("storage_light_secondary", "settling_primary")), pytest.raises(_Stop):
        measure.storage(ref_design)
    assert titles == ["vfy_sto_dark_secondary", "vfy_sto_lit_secondary"]


class _Stop(Exception):
    pass


def test_verify_tasks_carry_the_figures_their_specs_ask(ref_design):
    from pixelkit.verify import conditions
    from pixelkit.verify.run import plan
    grid = conditions.grid(ref_design, None, None, None)
    tasks, _mc = plan(ref_design, grid, 0)
    for c, groups, names in tasks:
        want = {s.fig.name for s in ref_design.spec if c in conditions.spec_conditions(s, grid)}
        assert set(names) == want, c.label
        assert set(groups) == set(measure.groups_for(sorted(want)))
