"""Pixels far beyond full well simulate, as silicon behaves; a failed point costs only itself.

Independent paths: the photodiode written as two diodes (bottom and sidewall, each a
plain junction whose forward charge ngspice continues from its own values) against the
kit's one card with its sidewall FCS; the charge reaching FD with anti-blooming against
the storage node's own light (I / gse); the node a failure names against the stimulus
that made it.
"""
import numpy as np
import pytest

from conftest import REF
from pixelkit.design import load_design


def _fw(design, kind):
    from pixelkit.chip.scene import i_floor
    return i_floor(design, kind, design.experiment.t_window, design.pixel.v_pd_reset - design.pixel.swing)


@pytest.mark.parametrize("kind", ["primary", "secondary"])
def test_sweep_to_1000x_full_well_with_and_without_anti_blooming(ref_design, kind):
    """1 pA to 1000 full wells over the window, EC holding the PD during storage and not: every
    point converges at the kit's own tolerances (no retry), the signal grows to full scale."""
    from pixelkit.sweep.run import run_sweep
    from pixelkit.sweep.space import parse_axis
    stim = "iph_p" if kind == "primary" else "iph_s"
    top = 1000 * _fw(ref_design, kind)
    sw = run_sweep(ref_design, [parse_axis(f"{stim}=log:1p:{top:.4g}:5"),
                                parse_axis(f"{kind}.timing.ec_hold=true,false")])
    assert all(p["ok"] and not p["message"] for p in sw.points), [p["message"] for p in sw.points]
    sig = np.array([p[f"signal_{kind}_V"] for p in sw.points]).reshape(5, 2)
    assert np.all(np.diff(sig[:3], axis=0) > 0)          # 1 pA .. ~full well: it grows
    assert sig[2].min() > 0.5 * sig[:, 0].max()


def _pd_deck(design, current, split):
    from pixelkit.circuits.devices import photodiode_model
    from pixelkit.spice.netlist import Element, Model, Netlist, Pwl, Tran
    t = design.tech.photodiode
    area, pj = design.primary.area, design.primary.perimeter
    card = photodiode_model(design.tech, design.temperature)[0]
    if split:   # bottom and sidewall as two plain junctions: nothing shared between them
        p = dict(card.params)
        bottom = Model("pd_bot", "d", (("level", 1), ("is", p["is"]), ("n", 1.0), ("cjo", t.cj), ("m", t.mj),
                                       ("vj", t.pb), ("tnom", p["tnom"])))
        side = Model("pd_sw", "d", (("level", 1), ("is", p["jsw"]), ("n", 1.0), ("cjo", t.cjsw), ("m", t.mjsw),
                                    ("vj", t.pbsw), ("tnom", p["tnom"])))
        models = (bottom, side)
        pd = (Element("Db", ("0", "pd"), "pd_bot", (("area", area),)),
              Element("Ds", ("0", "pd"), "pd_sw", (("area", pj),)))
    else:
        models = (card,)
        pd = (Element("Dpd", ("0", "pd"), card.name, (("area", area), ("pj", pj))),)
    el = (*pd, Element("Iph", ("pd", "0"), Pwl(((0.0, 0.0), (2e-6, current)))))
    return Netlist(title=f"pd_fwd_{'split' if split else 'card'}", elements=el, models=models,
                   analysis=Tran(5e-9, 20e-6, 0.0, 20e-9, uic=True), ic=(("pd", 2.0),), temperature_C=27.0)


@pytest.mark.parametrize("wells", [3, 1000])
def test_forward_biased_pd_matches_two_plain_junctions(ref_design, monkeypatch, wells):
    """A PD driven 3 and 1000 full wells (of the window) down into forward bias: the kit's card
    follows the split junctions within 1 mV all the way; with the default sidewall FCS (0.5) the
    3-well ramp stops where the sidewall's charge jumps (0.277 V forward)."""
    from pixelkit.errors import SimulationError
    from pixelkit.spice import simulate
    i = wells * _fw(ref_design, "primary")
    a = simulate(_pd_deck(ref_design, i, False))
    b = simulate(_pd_deck(ref_design, i, True))
    assert not a.meta.get("retried") and not b.meta.get("retried")
    assert float(a.at("v(pd)", 20e-6)) < -0.3                      # forward-biased, clamped
    tt = np.linspace(1e-6, 20e-6, 400)
    assert np.max(np.abs(a.at("v(pd)", tt) - b.at("v(pd)", tt))) < 1e-3
    if wells == 3:
        import pixelkit.circuits.devices as dv
        monkeypatch.setattr(dv, "sidewall_fc", lambda pd: 0.5)
        with pytest.raises(SimulationError) as e:
            simulate(_pd_deck(ref_design, i, False))
        assert "timestep too small" in e.value.message.lower()


def test_a_failed_point_is_left_out_and_named_with_its_array(tmp_path, monkeypatch):
    """The former card (FCS 0.5) and 3.3 V resets: the experiment's brightest coarse point fails;
    the experiment finishes from the other points, lists the failed one, and names the primary's
    own forward-biased node (ngspice itself blamed a secondary branch, vrs_s#branch)."""
    import pixelkit.circuits.devices as dv
    from pixelkit.experiments.thesis import run_experiment
    p = tmp_path / "r33.toml"
    p.write_text(REF.read_text().replace('v_pd_reset = "2.0 V"', 'v_pd_reset = "3.3 V"')
                 .replace('v_fd_reset = "2.0 V"', 'v_fd_reset = "3.3 V"'))
    monkeypatch.setattr(dv, "sidewall_fc", lambda pd: 0.5)
    e = run_experiment(load_design(p))
    assert len(e["failed_points"]) >= 1 and e["primary"]["swing_V"] > 1.0
    msg = e["failed_points"][0]["message"]
    assert "primary node x1.xp.pd" in msg and "forward-biased" in msg, msg


def test_bright_source_figures(ref_design):
    """1000 full wells: with anti-blooming the pixel reads at the top and the extra charge onto FD
    after its reset is its own light (I / gse, within 15 %); without, the primary reads dark
    (black sun) and FD takes ~100x that; the column recovers within 0.5 mV on the next row (on the
    read that settles: the reference design's own read carries the bright row into the next)."""
    from pixelkit.chip.bright import QUICK_FACTORS, figures
    rows = figures(ref_design, QUICK_FACTORS)
    by = {(r["array"], r["anti_blooming"], r["full_wells"]): r for r in rows}
    assert not any("failed" in r for r in rows)
    for kind in ("primary", "secondary"):
        on, base = by[(kind, True, 1000.0)], by[(kind, True, 1.0)]
        assert on["of_full_well_signal"] > 0.95 and not on["black_sun"]
        extra = on["fd_after_reset_e"] - base["fd_after_reset_e"]
        assert extra == pytest.approx(on["fd_light_e"], rel=0.15, abs=5.0), kind
        assert all(abs(r["recovery_V"]) < 0.5e-3 for r in rows)
    off = by[("primary", False, 1000.0)]
    assert off["black_sun"] and off["fd_after_reset_e"] > 50 * off["fd_light_e"]


def test_bright_deck_reads_its_column_alone_as_the_whole_dual_column(ref_design, monkeypatch):
    """The secondary's bright deck keeps only the column the figures read (chip.bright._first_column):
    the dual column's other secondary columns are copies under the same light that share only ideal
    sources with it. The whole dual column's deck, simulated here, reads the same dark, 1000-full-well
    and dark rows there within 0.3 mV (the two decks' step sequences differ: the figures moved by up
    to 0.13 mV, both designs and anti-blooming settings, 1 and 1000 full wells)."""
    import pixelkit.chip.bright as bright
    from pixelkit.circuits.array import frame_timings
    from pixelkit.measure.pixel import levels
    from pixelkit.spice import simulate_many

    def secondary(plan):
        return next(net for _, _, kind, net in plan if kind == "secondary")
    alone = secondary(bright.decks(ref_design, (1000.0,), (None,)))
    monkeypatch.setattr(bright, "_first_column", lambda net, kind, n: net)
    whole = secondary(bright.decks(ref_design, (1000.0,), (None,)))
    nodes = {x for e in alone.elements for x in e.nodes}
    assert "col_s_0" in nodes and "in_col_s_0" in nodes and not any(x.endswith(("col_s_1", "col_s_2")) for x in nodes)
    assert len(alone.elements) < len(whole.elements)
    t = frame_timings(ref_design, ref_design.experiment.t_window, bright.ROWS)["secondary"]
    a, w = simulate_many([alone, whole])
    for row in range(bright.ROWS):
        sig_a, rst_a = levels(a, "col_s_0", t, row)
        sig_w, rst_w = levels(w, "col_s_0", t, row)
        assert abs((rst_a - sig_a) - (rst_w - sig_w)) < 0.3e-3, row
