"""pixelkit verify on small grids: failing specs named with their corners, physics directions over
the corners, power against bias currents x supply, Monte Carlo yield and its refusals.

Independent paths: physics (settling slows at ss, dark current and kT/C grow with temperature,
power follows the supply), the analytic power estimate (bias currents x supply x duty, the OTA's
mirror ratios), a nominal (mismatch-free) simulation for the yield's 50 % point, and the Pelgrom
derivation of the column offset for the kit's own mismatch draw.
"""
import copy
import json
import math
import tomllib
from dataclasses import replace
from pathlib import Path

import pytest

from conftest import REF, ROOT, run_cli
from pixelkit.design import load_design
from pixelkit.errors import ConfigError, PixelkitError
from pixelkit.schema import to_toml
from pixelkit.verify import conditions, measure
from pixelkit.verify.run import verify

BASE = tomllib.loads(REF.read_text())


def _design(tmp_path: Path, specs: dict, verify_table: dict | None = None, **top) -> Path:
    raw = copy.deepcopy(BASE)
    raw["spec"] = specs
    raw["verify"] = {**raw.get("verify", {}), **(verify_table or {})}
    raw.update(top)
    p = tmp_path / "d.toml"
    p.write_text(to_toml(raw))
    return p


def test_impossible_spec_fails_naming_itself_and_its_corners(tmp_path):
    """The AFE's finite gain leaves ~0.2 % (measure.afe): 0.01 % is impossible; exit 1 names
    that spec and every condition, the possible spec stays unnamed."""
    f = _design(tmp_path, {"afe_impossible": {"figure": "afe_gain_error", "max": "0.01 %"},
                           "afe_gain_error": {"max": "1 %"}}, {"mc": 0})
    code, out, err = run_cli("verify", f, "--corners", "tt,ss", "--temperatures", "27degC", "--supplies", "0%",
                             "--out", tmp_path / "v", "--json", timeout=300)
    assert code == 1, err
    assert "afe_impossible at tt 27degC +0%, ss 27degC +0%" in err
    assert "afe_gain_error at" not in err
    rows = {r["spec"]: r for r in json.loads(out)["rows"]}
    assert rows["afe_impossible"]["status"] == "fail" and rows["afe_gain_error"]["status"] == "pass"
    assert rows["afe_impossible"]["margin"] < 0 < rows["afe_gain_error"]["margin"]
    csv = (tmp_path / "v" / "signoff.csv").read_text().splitlines()
    assert csv[0].startswith("spec,limit,worst condition") and len(csv) == 3
    assert json.loads((tmp_path / "v" / "signoff.json").read_text())["failed"] == ["afe_impossible"]


def test_a_spec_not_run_anywhere_is_never_exit_0(tmp_path):
    """Issue 44: a spec restricted to a temperature the grid does not run is NOT RUN: exit 5 (the
    team's "nothing failed but something asked was not measured"), said on stderr; a failing spec
    beside it takes precedence (exit 1). One AFE condition (~1 s)."""
    hot = {"figure": "afe_gain_error", "max": "1 %", "temperatures": ["85 degC"]}
    args = ("--corners", "tt", "--temperatures", "27degC", "--supplies", "0%", "--json")
    f = _design(tmp_path, {"afe_gain_error": {"max": "1 %"}, "afe_hot": hot}, {"mc": 0})
    code, out, err = run_cli("verify", f, *args, "--out", tmp_path / "v", timeout=300)
    assert code == 5, err
    assert "not measured (exit 5): afe_hot: none of its conditions" in err
    r = json.loads(out)
    assert r["unmeasured"] == ["afe_hot"] and not r["failed"]
    f = _design(tmp_path, {"afe_impossible": {"figure": "afe_gain_error", "max": "0.01 %"}, "afe_hot": hot}, {"mc": 0})
    code, out, err = run_cli("verify", f, *args, "--out", tmp_path / "w", timeout=300)
    assert code == 1 and "afe_impossible at tt 27degC +0%" in err, err


def test_verdict_exit_rule():
    """The one rule verify, report and close decide their status with: 1 > 4 > 5 > 0; a status the
    rule does not know, or no item at all, is never a pass."""
    from pixelkit.errors import verdict_exit
    assert verdict_exit(["pass", "pass"]) == 0
    assert verdict_exit(["pass", "not run"]) == 5
    assert verdict_exit(["pass", "not measured"]) == 5
    assert verdict_exit(["pass", "skipped"]) == 5 and verdict_exit(["pass", "weird"]) == 5
    assert verdict_exit([]) == 5
    assert verdict_exit(["pass", "not run"], simulation_failed=True) == 4
    assert verdict_exit(["fail", "not run"], simulation_failed=True) == 1
    assert verdict_exit(["PASS", "FAIL"]) == 1


def _at(design, corner, temp_c=27.0, supply=0.0):
    return conditions.at(design, conditions.Condition(corner, temp_c + 273.15, supply))


def test_settling_slower_at_ss_than_ff(thesis_read_design, ref_design):
    """Slow devices (ss) leave a larger settling error at the same clocks than fast ones (ff); the
    same corner twice gives the same number (the inequality is not the noise of the solver).
    On the read of [Thesis2019] (400 nA load, the default phases: it does not settle, issue
    27): both arrays read worse at ss. The reference design's settled read (designs/dual_pixel_revA.toml)
    settles at both corners."""
    old = thesis_read_design
    ss = measure.settling(_at(old, "ss"))
    ff = measure.settling(_at(old, "ff"))
    assert ss["secondary"] > 1.5 * ff["secondary"] and ss["primary"] > 1.5 * ff["primary"], (ss, ff)
    assert measure.settling(_at(old, "ff")) == ff
    for corner in ("ss", "ff"):
        assert max(measure.settling(_at(ref_design, corner)).values()) < 0.5e-3, corner


def test_settling_figure_is_the_read_not_the_solver():
    """The settling figure is the difference of two transient reads: at the engine's default reltol
    1e-5 each read's integration error enters it. On the GF180 port's revision B at tt -20 degC +10 %
    the default tolerances give 0.57 mV for the secondary (the 0.5 mV limit), a run ten times tighter
    (reltol 1e-7) 0.02 mV; verify's figure (reltol 1e-6, ``chip.frame.CONVERGED``) is the latter within
    0.05 mV: independent path, the same decks integrated to convergence."""
    import numpy as np
    from pixelkit.chip.frame import simulate_frame
    from pixelkit.chip.scene import default_stimulus
    d = _at(load_design(ROOT / "designs" / "dual_pixel_gf180_revB.toml"), "tt", -20.0, 0.1)
    stim = default_stimulus(d, d.experiment.t_window)
    ip, is_ = np.full((2, 1), stim["iph_p"]), np.full((2, d.secondary_per_pixel), stim["iph_s"])

    def worst(options):
        f = simulate_frame(d, ip, is_, with_afe=True, split="columns", settling=True, jobs=1, options=options)
        return {k: float(np.nanmax(np.abs(f.settling[k]))) for k in ("primary", "secondary")}
    figure, tight, loose = measure.settling(d), worst((("reltol", 1e-7), ("abstol", 1e-12))), worst(None)
    for k in ("primary", "secondary"):
        assert figure[k] == pytest.approx(tight[k], abs=0.05e-3), (k, figure, tight)
    assert loose["secondary"] - tight["secondary"] > 0.2e-3, (loose, tight)


def test_pd_dark_drop_and_ktc_grow_with_temperature(ref_design):
    dark = [measure.dark(_at(ref_design, "tt", t)) for t in (-20.0, 27.0, 85.0)]
    noise = [measure.noise(_at(ref_design, "tt", t)) for t in (-20.0, 27.0, 85.0)]
    for kind in ("primary", "secondary"):
        d = [x[kind] for x in dark]
        assert 0 < d[0] < d[1] < d[2], d
        # the kit's dark law doubles every 7 K: from 27 to 85 degC at least 2^(58/7 - 2) more
        assert d[2] / d[1] > 2 ** (58 / 7 - 2)
        k = [x[kind]["ktc_e"] for x in noise]
        assert k[0] < k[1] < k[2]
        # kT/C in electrons goes as sqrt(T) (C changes little with T)
        assert k[2] / k[0] == pytest.approx(math.sqrt(358.15 / 253.15), rel=0.02)


def test_power_scales_with_supply_and_matches_bias_currents(thesis_read_design, ref_design):
    """Every block is fed from the supply at a bias current the supply does not set: power goes as
    V (ratio 1.1 / 0.9 within 2 %). SPICE per block against bias currents x supply x duty. With a
    column precharge (the settled read) the follower also recharges the grounded line and C11 (in
    the estimate) and drives the precharge switch while both conduct (a crowbar, not in it): there
    the estimate is a lower bound."""
    lo, nom, hi = (measure.power(_at(thesis_read_design, "tt", 27.0, s)) for s in (-0.1, 0.0, 0.1))
    assert lo["chip_W"] < nom["chip_W"] < hi["chip_W"]
    assert hi["chip_W"] / lo["chip_W"] == pytest.approx(1.1 / 0.9, rel=0.02)
    est = nom["estimate"]["chip_blocks_W"]
    for block, rel in (("bias", 0.01), ("read", 0.10), ("afe", 0.01)):
        assert nom["chip_blocks_W"][block] == pytest.approx(est[block], rel=rel), block
    pre = measure.power(ref_design)
    no_pre = {k: replace(getattr(ref_design, k), timing=replace(getattr(ref_design, k).timing, pre_on=None,
                                                                         pre_off=None)) for k in ("primary", "secondary")}
    bare = measure.power(replace(ref_design, **no_pre))
    assert bare["chip_blocks_W"]["read"] == pytest.approx(bare["estimate"]["chip_blocks_W"]["read"], rel=0.10)
    est_pre = pre["estimate"]["chip_blocks_W"]["read"]
    assert est_pre > 1.3 * bare["estimate"]["chip_blocks_W"]["read"]
    assert est_pre < pre["chip_blocks_W"]["read"] < 3 * est_pre
    # the transistor-level OTA draws its own current: SPICE against its mirror ratios (70 uA)
    ota = measure.power(replace(ref_design, afe=replace(ref_design.afe, opamp="ota")))
    assert ota["chip_blocks_W"]["afe"] == pytest.approx(ota["estimate"]["chip_blocks_W"]["afe"], rel=0.10)


def test_yield_at_the_nominal_median_is_half(tmp_path):
    """A limit at the mismatch-free nominal value: mismatch of the AFE capacitors and switches is
    symmetric about it, so about half of the samples pass; the Clopper-Pearson interval holds 50 %.
    Moved 3 sigma into the distribution, the yield interval leaves 50 % (the check can fail)."""
    d = load_design(_design(tmp_path, {"afe_gain_error": {"max": "1 %"}}, {"mc": 40, "seed": 3}))
    nominal = measure.figures({"afe": measure.afe(d)})["afe_gain_error"]
    first = verify(d, corners=("tt",), temperatures=(300.15,), supplies=(0.0,), mc_full=True)
    values = first["mc_values"]["afe_gain_error"]
    assert first["mc"]["source"] == "library" and len(values) == 40
    at_nominal = replace(d, spec=(replace(d.spec[0], hi=nominal),))
    r = verify(at_nominal, corners=("tt",), temperatures=(300.15,), supplies=(0.0,), mc_full=True)["rows"][0]["yield"]
    lo, hi = r["interval"]
    assert lo <= 0.5 <= hi, r
    assert abs(r["margin_sigma"]) < 0.5
    import numpy as np
    sd = float(np.std(values, ddof=1))
    shifted = replace(d, spec=(replace(d.spec[0], hi=nominal - 3 * sd),))
    y = verify(shifted, corners=("tt",), temperatures=(300.15,), supplies=(0.0,), mc_full=True)["rows"][0]["yield"]
    assert y["interval"][1] < 0.5 and y["margin_sigma"] < -2


def test_monte_carlo_is_reproducible_and_resumes_from_the_cache(tmp_path):
    from pixelkit.spice.engine import observe
    d = load_design(_design(tmp_path, {"afe_gain_error": {"max": "1 %"}}, {"mc": 5, "seed": 11}))
    kw = dict(corners=("tt",), temperatures=(300.15,), supplies=(0.0,))
    a = verify(d, **kw)
    runs = []
    with observe(lambda event, n: runs.append(n) if event == "queued" else None):
        b = verify(d, **kw)
    assert not runs                                # nothing simulated again
    assert a["mc_values"] == b["mc_values"]
    other = verify(replace(d, verify=replace(d.verify, seed=12)), **kw)
    assert other["mc_values"] != a["mc_values"]   # another seed, other chips


def test_zero_spread_monte_carlo_is_an_error(tmp_path, monkeypatch):
    """Devices that carry no mismatch (CACE's trap: a Monte Carlo over a netlist that lost its
    mismatch flags reads min = typ = max and passes) are refused, never passed."""
    from pixelkit.verify import mismatch
    monkeypatch.setattr(mismatch, "apply", lambda net, design, draw: net)
    d = load_design(_design(tmp_path, {"afe_gain_error": {"max": "1 %"}}, {"mc": 3}))
    with pytest.raises(PixelkitError, match="zero spread of afe_gain_error"):
        verify(d, corners=("tt",), temperatures=(300.15,), supplies=(0.0,))


LEVEL1 = """* level-1 MOSFETs without mismatch statistics (a test library)
.model nfet_03v3 nmos (level=1 vto=0.7 kp=170e-6 gamma=0 lambda=0.02 cgso=1e-10 cgdo=1e-10 cj=9.7e-4 cjsw=1.6e-10)
.model pfet_03v3 pmos (level=1 vto=-0.75 kp=60e-6 gamma=0 lambda=0.02 cgso=1e-10 cgdo=1e-10 cj=9.7e-4 cjsw=1.6e-10)
"""


def _level1_design(tmp_path: Path, avt: bool, specs: dict) -> Path:
    tech = tomllib.loads((ROOT / "pixelkit" / "tech" / "builtin" / "c35_thesis.toml").read_text())
    (tmp_path / "models").mkdir()
    (tmp_path / "models" / "level1.lib").write_text(LEVEL1)
    tech["mos"]["kind"] = "model"
    tech["models"] = {"folder": "models", "default_corner": "tt", "corners": {"tt": ["include level1.lib"]}}
    if avt:
        tech["mismatch"].update(mos_avt_n="5 mV*um", mos_avt_p="5 mV*um")
    (tmp_path / "tech.toml").write_text(to_toml(tech))
    return _design(tmp_path, specs, {"mc": 60, "seed": 5}, technology=str(tmp_path / "tech.toml"))


def test_kit_pelgrom_draw_where_the_library_has_none(tmp_path):
    """A library without statistics: the kit draws each MOSFET's threshold (A_VT / sqrt(W L)) and
    says so. Check against the derivation for level-1 devices (no body effect): the column level
    at a fixed FD moves by G (dVT_sf + (Vov_sf / Vov_ld)(dVT_bias - dVT_ld)), Vov_sf / Vov_ld =
    sqrt((W/L)_ld / (W/L)_sf), so sigma = G sqrt(s_sf^2 + r^2 (s_ld^2 + s_bias^2))."""
    f = _level1_design(tmp_path, True, {"read_noise_primary": {"max": "1000 e-"}})
    d = load_design(f)
    from pixelkit.verify import mismatch
    assert mismatch.source(d) == "pelgrom"
    from pixelkit.circuits.testbench import sf_bench
    from pixelkit.spice import simulate_many
    levels, gains = [], []
    for i in range(60):
        draw = mismatch.Draw(5, i, "pelgrom")
        v = d.pixel.v_fd_reset
        nets = [mismatch.apply(sf_bench(d, v + dv, title="t"), d, draw) for dv in (-0.05, 0.0, 0.05)]
        lo, mid, hi = simulate_many(nets, jobs=2)
        levels.append(float(mid["v(col)"][0]))
        gains.append(float((hi["v(col)"][0] - lo["v(col)"][0]) / 0.1))
    import numpy as np
    dev = d.pixel.devices
    s = lambda w, l: 5e-9 / math.sqrt(w * l)          # noqa: E731
    r = math.sqrt((dev.load_w / dev.load_l) / (dev.sf_w / dev.sf_l))
    g = float(np.mean(gains))
    expect = g * math.sqrt(s(dev.sf_w, dev.sf_l) ** 2 + r ** 2 * 2 * s(dev.load_w, dev.load_l) ** 2)
    assert float(np.std(levels, ddof=1)) == pytest.approx(expect, rel=0.25)
    # the same decks without the draw: one level (nothing else varies)
    r0 = verify(d, corners=("tt",), temperatures=(300.15,), supplies=(0.0,), mc=0)
    assert r0["mc"]["samples"] == 0


def test_no_mismatch_anywhere_is_refused_before_running(tmp_path):
    d = load_design(_level1_design(tmp_path, False, {"afe_gain_error": {"max": "1 %"}}))
    with pytest.raises(ConfigError) as err:
        verify(d, corners=("tt",), temperatures=(300.15,), supplies=(0.0,), mc=4)
    assert err.value.field == "mismatch.mos_avt_n" and "zero spread" in err.value.allowed


def test_dask_cluster_gives_the_local_table(tmp_path, monkeypatch):
    """The same grid on a Dask LocalCluster (2 worker processes, their own empty cache) and on the
    local threads (a second empty cache): the same values at every condition, and the workers did
    the simulating. The Monte Carlo of 22 against min_yield 99 % cannot decide at its first look
    (20 samples all passing: interval from 80 %), so its second stage is added while the first
    runs out: both ways the same 22 samples."""
    from dask.distributed import LocalCluster
    d = load_design(_design(tmp_path, {"afe_gain_error": {"max": "1 %"}, "pd_dark_drop_primary": {"max": "10 mV"}},
                            {"mc": 22, "seed": 4, "min_yield": "99 %"}))
    kw = dict(corners=("tt", "ss"), temperatures=(300.15,), supplies=(0.0, 0.1))
    dask_cache, local_cache = tmp_path / "dask_cache", tmp_path / "local_cache"
    monkeypatch.setenv("PIXELKIT_CACHE", str(dask_cache))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        remote = verify(d, scheduler=cluster.scheduler_address, **kw)
    assert len(list((dask_cache / "sim").glob("*/*.entry"))) > 4
    monkeypatch.setenv("PIXELKIT_CACHE", str(local_cache))
    local = verify(d, jobs=2, **kw)
    assert [c["figures"] for c in remote["conditions"]] == [c["figures"] for c in local["conditions"]]
    assert remote["mc_values"] == local["mc_values"] and len(local["mc_values"]["afe_gain_error"]) == 22
    assert remote["mc"]["stop"] == local["mc"]["stop"] and "not every yield decided" in local["mc"]["stop"]


def test_post_layout_view_lowers_the_pd_conversion_gain_by_its_wiring(tmp_path):
    """verify --post-layout runs every measurement on the extracted view: the PD-referred
    conversion gain drops by C_node / (C_node + the wiring the extraction put on the PD node)
    (independent path: the junction model's C(V) and the extraction's own capacitance). A
    technology without a process stack is refused, never run as the schematic."""
    gf = ROOT / "designs" / "dual_pixel_gf180.toml"
    raw = tomllib.loads(gf.read_text())
    raw["spec"] = {"pd_conversion_gain_primary": {"min": "1 uV/e-"}, "pd_conversion_gain_secondary": {"min": "1 uV/e-"}}
    (tmp_path / "g.toml").write_text(to_toml(raw))
    d = load_design(tmp_path / "g.toml")
    kw = dict(corners=("tt",), temperatures=(300.15,), supplies=(0.0,), mc=0)
    sch = verify(d, **kw)
    post = verify(d, post_layout=True, **kw)
    assert (sch["view"], post["view"]) == ("schematic", "post-layout")
    from pixelkit.physics.subpixel import pd_node
    from pixelkit.verify.run import post_layout_view
    pl = post_layout_view(d).post_layout
    for i, kind in enumerate(("primary", "secondary")):
        c = float(pd_node(d, kind, parasitics=True).capacitance(d.pixel.v_pd_reset))
        ratio = post["rows"][i]["value"] / sch["rows"][i]["value"]
        assert ratio == pytest.approx(c / (c + pl.node_wiring(kind, "pd")), rel=0.01), kind
        assert ratio < 0.99
    with pytest.raises(ConfigError, match="stack"):
        verify(load_design(_design(tmp_path, {"afe_gain_error": {"max": "1 %"}})), post_layout=True, **kw)


def test_settling_specs_fail_on_a_design_that_does_not_settle(tmp_path):
    """The design's own settling specs (0.5 mV) through `pixelkit verify`: the reference design's
    read (400 nA load, the default phases; tens of mV of row-to-row memory, test_settling) fails both
    and names them; the settled read passes both at the same condition."""
    from former_design import former
    out = {}
    for name, text in (("former", former()), ("settled", REF.read_text())):
        raw = tomllib.loads(text)
        raw["spec"] = {k: v for k, v in raw["spec"].items() if k.startswith("settling_")}
        raw["verify"] = {**raw.get("verify", {}), "mc": 0}
        p = tmp_path / f"{name}.toml"
        p.write_text(to_toml(raw))
        code, stdout, err = run_cli("verify", p, "--corners", "tt", "--temperatures", "27degC", "--supplies", "0%",
                                    "--out", tmp_path / name, "--json", timeout=600)
        out[name] = (code, {r["spec"]: r["status"] for r in json.loads(stdout)["rows"]}, err)
    assert out["former"][0] == 1 and "settling_primary at" in out["former"][2], out["former"]
    assert out["former"][1] == {"settling_primary": "fail", "settling_secondary": "fail"}
    assert out["settled"][0] == 0 and set(out["settled"][1].values()) == {"pass"}, out["settled"]
