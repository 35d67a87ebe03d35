"""Settling of a frame's rows: the sampled signal level against the same read with a long S1.

Independent paths: the reference is another operating point of the circuit (S1 held four
row times longer), not the frame's own numbers; and the physics the test writes down
itself: under uniform light every row of a column must read the same level, so the
settled levels of a column whose raw samples differ row to row by > 50 mV must agree.
The unsettled design is the thesis's read (designs/dual_pixel_revA_thesis_read.toml: 400 nA load, the
default read); the settled one is the reference, designs/dual_pixel_revA.toml.
"""
import json
from pathlib import Path

import numpy as np
import pytest

from conftest import REF
from former_design import former
from pixelkit.design import load_design

UNIFORM = 0.5   # of the primary's full scale


def _former(tmp_path):
    p = tmp_path / "former.toml"
    p.write_text(former())
    return p


def _photo(design, levels):
    from pixelkit.chip.scene import photocurrents
    return photocurrents(design, len(levels), 1, np.array([[v] * design.secondary_per_pixel for v in levels]), "fs")


def _frame(design, rows=3, levels=None, options=None):
    from pixelkit.chip.frame import simulate_frame
    ph = _photo(design, [UNIFORM] * rows if levels is None else levels)
    # the light as `pixelkit array` gives it: the charge of t_int in the window, then the real light
    # (without ``compression`` FD would keep the window's light, 62x the primary's, through the read)
    return simulate_frame(design, ph.iph_p, ph.iph_s, with_afe=True, settling=True, options=options,
                          compression=ph.compression)


def test_array_tells_an_unsettled_frame_from_a_settled_one(tmp_path, cli):
    outs = {}
    for name, path in (("former", _former(tmp_path)), ("settled", REF)):
        code, out, err = cli("array", path, "--rows", 3, "--cols", 1, "--afe", "--scene", "uniform", "--json",
                             "--out", tmp_path / name)
        assert code == 0, err
        outs[name] = json.loads(out)
    bad, good = outs["former"], outs["settled"]
    assert not bad["verdict"]["ok"] and "settling beyond its limit" in bad["verdict"]["text"]
    assert bad["settling"]["worst_V"]["primary"] > 0.05                 # tens of mV: C11 + line unsettled
    assert bad["settling"]["limit_V"] == {"primary": 0.5e-3, "secondary": 0.5e-3}   # the design's specs
    assert [1, 0] in bad["settling"]["beyond"]["primary"] and [2, 0] in bad["settling"]["beyond"]["primary"]
    assert good["verdict"] == {"ok": True, "text": "ok"}
    assert max(good["settling"]["worst_V"].values()) < 0.5e-3
    assert "settling_V" in (tmp_path / "former" / "frame.csv").read_text().splitlines()[0]


def test_settled_levels_are_the_same_in_every_row_of_a_uniform_column(tmp_path):
    """The former design's double-sampled signals remember the previous row (row 0 starts from
    another state); signal - settling error agrees row to row within the storage drift."""
    f = _frame(load_design(_former(tmp_path)))
    raw = f.signal["primary"][:, 0]                  # the double-sampled signal as read
    settled = raw - f.settling["primary"][:, 0]
    assert abs(raw[1] - raw[0]) > 0.05
    assert np.ptp(settled) < 3e-3          # rows wait 2 us longer each: ~1 mV/row of FD drift
    assert np.all(np.abs(f.settling["primary"][1:, 0]) > 0.05)


def test_reference_is_converged_and_flags_itself_when_too_short(ref_design, monkeypatch):
    """A reference twice as long moves the settled level by < 0.1 mV (at converged tolerances: at
    the kit's reltol 1e-5 two decks' reset levels scatter by ~0.2 mV); one row time is too short
    to settle and the check says so (NaN and a note), instead of reporting a number."""
    import pixelkit.chip.settling as st
    from pixelkit.chip.frame import CONVERGED
    levels = {}
    for factor in (4, 8):
        monkeypatch.setattr(st, "LONG_S1", factor)
        f = _frame(ref_design, rows=2, options=CONVERGED)
        levels[factor] = {k: f.signal[k] - f.settling[k] for k in f.settling}   # the settled signals
        assert not f.settling_notes
    for k in levels[4]:
        assert np.max(np.abs(levels[4][k] - levels[8][k])) < 1e-4, k
    monkeypatch.setattr(st, "LONG_S1", 1)
    f = _frame(ref_design, rows=2)
    assert np.isnan(f.settling["primary"]).all() and "has not settled" in f.settling_notes[0]


@pytest.mark.parametrize("which", ["ref_design", "thesis_read_design"])
def test_reference_from_where_the_reads_part_is_the_whole_long_read(which, request):
    """The frame simulates its long-S1 reference only from the instant it parts from the read, from
    the read's state there (chip.frame._continued). The whole long-S1 deck from t = 0, built and read
    here, gives the same settling errors within 0.02 mV at converged tolerances (measured 0.002 -
    0.005 mV), on the read that settles and on the one that is 0.23 V off."""
    from pixelkit.chip.frame import CONVERGED, STEPS_PER_ROW
    from pixelkit.chip.settling import reference_timings, settled_level
    from pixelkit.circuits.array import Tile, array_bench, frame_timings
    from pixelkit.spice import simulate_many
    design = request.getfixturevalue(which)
    f = _frame(design, levels=[1.0, 0.05], options=CONVERGED)     # row 0 (the other row off, as one device)
    ph = _photo(design, [1.0, 0.05])
    t_exp = design.experiment.t_window
    tm = frame_timings(design, t_exp, 2)
    step = min(t.t_row for t in tm.values()) / STEPS_PER_ROW
    for kind, s in (("primary", "p"), ("secondary", "s")):
        tm_ref = reference_timings(tm, kind)
        net = array_bench(design, ph.iph_p, ph.iph_s, Tile((kind,), (0,), (0,)), t_exp, True, None, step,
                          title=f"whole_long_s1_{s}", tm=tm_ref, compression=ph.compression)
        (res,) = simulate_many([net], options=CONVERGED)
        sig, ok_s = settled_level(res, f"col_{s}_0", tm_ref[kind], tm[kind], 0)
        rst, ok_r = settled_level(res, f"col_{s}_0", tm_ref[kind], tm[kind], 0, which="reset")
        assert ok_s and ok_r
        whole = f.signal[kind][0, 0] - (rst - sig)
        assert abs(f.settling[kind][0, 0] - whole) < 2e-5, (kind, f.settling[kind][0, 0], whole)
    if which == "thesis_read_design":
        assert abs(f.settling["primary"][0, 0]) > 0.05          # the unsettled read stays unsettled


def test_verdict_names_what_is_not_ok():
    from pixelkit.chip.settling import summary
    from pixelkit.cli.array import verdict
    s = summary({"primary": np.array([[0.0, 2e-3], [1e-4, np.nan]])})
    assert s["beyond"]["primary"] == [[0, 1]] and s["not_measured"] == 1
    v = verdict({**s, "notes": []}, {"primary": 2, "secondary": 0}, [])
    assert not v["ok"] and "clipped subpixels: primary 2" in v["text"] and "primary 1" in v["text"]
    assert verdict(None, {"primary": 0}, [])["text"] == "NOT ok: settling not measured"


def test_settled_design_reads_its_sizing_targets_on_a_frame_with_the_afe(ref_design, experiment,
                                                                        thesis_read_design, thesis_read_experiment):
    """The 5 % / mid-scale point of the [Thesis2019] simulation experiment (one dual pixel, its column, no AFE) read
    on a frame column with the AFE, after a full row and after a dark one: within 3 % of the
    target fractions; the thesis's own read gives 0.74 and 0.12 there (its column does not settle)."""
    from pixelkit.chip.targets import frame_targets, worst_departure
    t = frame_targets(ref_design, experiment)
    assert not t["failures"] and worst_departure(t) < 0.03, t["arrays"]
    assert worst_departure(frame_targets(thesis_read_design, thesis_read_experiment)) > 0.3


@pytest.mark.slow
def test_27_row_column_settles_at_both_clocks(ref_design):
    """Every row of a 27-row dual column with its AFE (primary 500 kHz, secondary 1 MHz), rows
    cycling dark / 5 % / 30 % / full / 3x and 30x full well, within 0.5 mV of the long read at
    converged tolerances (reltol 1e-6): measured 0.007 / 0.30 mV."""
    from pixelkit.chip.frame import CONVERGED
    cycle = [0.05, 1.0, 0.0, 30.0, 0.3, 0.8, 0.02, 3.0, 0.5]
    f = _frame(ref_design, levels=[cycle[r % len(cycle)] for r in range(27)], options=CONVERGED)
    assert not f.failures and not f.retried and not f.settling_notes
    for k in ("primary", "secondary"):
        assert np.nanmax(np.abs(f.settling[k])) < 0.5e-3, k


def test_bright_rows_at_ss_85c_low_supply_leave_what_the_2_row_spec_does_not_see(ref_design):
    """The corner docs/timing-and-settling.md reports failing, ss 85 degC -10 % supply: a dual column with
    its AFE whose rows cycle dark / 5 % / 30 % / full / 3x and 30x full well (one cycle, 9 rows; the
    27-row column of the slow test above reads 1.439 mV there, the docs' figure), at converged
    tolerances, against the long read. The secondary keeps more than the 0.5 mV limit after a bright
    row (measured 1.310 mV, 9 rows) while the primary settles (0.004 mV), and verify's own settling
    figure at the same corner (a 2-row mid-light frame) stays below the limit (docs/verify.md quotes them): what
    docs/verify.md says its settling spec does not cover."""
    from pixelkit.chip.frame import CONVERGED
    from pixelkit.verify import conditions, measure
    d = conditions.at(ref_design, conditions.Condition("ss", 358.15, -0.1))
    cycle = [0.05, 1.0, 0.0, 30.0, 0.3, 0.8, 0.02, 3.0, 0.5]
    f = _frame(d, levels=cycle, options=CONVERGED)
    assert not f.failures and not f.retried and not f.settling_notes
    assert np.nanmax(np.abs(f.settling["primary"])) < 0.5e-3
    assert 0.9e-3 < np.nanmax(np.abs(f.settling["secondary"])) < 2e-3
    spec = measure.settling(d)
    assert max(spec.values()) < 0.5e-3
    # docs/verify.md quotes these figures (``stl:KEY`` marks, mV): a change that moves one fails here
    import os
    from docsite import figures
    figs = {"bright_secondary": float(np.nanmax(np.abs(f.settling["secondary"]))) * 1e3,
            **{f"verify_{k}": v * 1e3 for k, v in spec.items()}}
    page = Path(__file__).resolve().parents[1] / "docs" / "verify.md"
    if os.environ.get("PIXELKIT_DOCS_REWRITE"):
        figures.update(None, [page], getters={"stl": figs.__getitem__})
    bad, n = figures.check(None, [page], getters={"stl": figs.__getitem__})
    assert not bad, "\n".join(f"verify.md:{b['line']}: {b['key']}: quoted {b['quoted']}, now "
                              f"{b.get('now') or b.get('why')}" for b in bad)
