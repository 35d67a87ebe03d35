"""``pixelkit close`` on a pixel read by role (the 4T of designs/pixel4t_gf180.toml), close's own loop.

The known optimum comes from a derivation, not from close: the lowest TG rail whose transfer leaves a
dark frame after a half-full-well one below 0.1 % image lag. The barrier-limited transfer integrates
exactly (``physics.ppd.Ppd.residual``: dQ/dt = -a (exp(Q / Q_T) - 1), checked against a numerical ODE
solution in tests/test_pixel4t.py) and ``families.pixel4t.model.lag_electrons`` follows the charge over
the read, the next shutter and the next read; its root in V_TG (scipy's brentq) is the optimum. The
lag is exponential in the TG rail (0.29 % at 2.90 V, 2e-5 % at 2.95 V), so the SPICE bench and the
closed form (8 % apart in lag, tests/test_pixel4t.py) put the edge within a mV; close's grid is 1 mV
and its tolerance 2.5 mV. The revision close writes is then re-verified by ``pixelkit verify`` alone.
"""
import json

import pytest

from conftest import ROOT
from pixelkit.schema import to_toml

DESIGN = ROOT / "designs" / "pixel4t_gf180.toml"


def _design(tmp_path, levels_tg_high: str, spec: dict, close: dict, name: str = "p4t.toml"):
    """designs/pixel4t_gf180.toml (its comments kept) at one condition, with these [spec] and [close]."""
    text = DESIGN.read_text().replace('tg_high = "3.3 V"', f'tg_high = "{levels_tg_high}"')
    assert f'tg_high = "{levels_tg_high}"' in text
    p = tmp_path / name
    p.write_text(text.split("\n[verify]")[0] + "\n" + to_toml({
        "verify": {"corners": ["tt"], "temperatures": ["27 degC"], "supplies": ["0 %"], "mc": 0},
        "spec": spec, "close": close}))
    return p


def test_close_lowers_the_tg_rail_to_the_derived_lag_edge_and_verify_passes_what_it_wrote(tmp_path, cli):
    p = _design(tmp_path, "2.85 V", {"image_lag": {"max": "0.1 %"}},
                {"objective": "min levels.tg_high", "tolerance": 0.005,
                 "knobs": {"levels.tg_high": {"min": "2.8 V", "max": "3.3 V", "step": "1 mV"}}})
    out = tmp_path / "p4t_closed.toml"
    code, stdout, err = cli("close", p, "--out", out, "--json")
    assert code == 0, err
    r = json.loads(stdout)
    assert r["status"] == "closed" and r["passes"]
    start = r["iterations"][0]
    assert start["specs"]["image_lag"]["margin_pct"] < -100      # 2.85 V: ~1.1 % lag, the spec fails
    from pixelkit.units import quantity
    v_close = quantity(r["knobs"][0]["value"], "V", "levels.tg_high")

    # the derivation, at the charge the bench put in the bright frame of the written revision
    from scipy.optimize import brentq
    from pixelkit.circuits.pixel4t import ppd_model
    from pixelkit.constants import Q
    from pixelkit.families.pixel4t import model
    from pixelkit.families.pixel4t.design import load_pixel4t_design, tg_channel
    from pixelkit.rolepix.signal import lag_deck
    d = load_pixel4t_design(out)
    assert d.levels.tg_high == pytest.approx(v_close, abs=1e-9)
    q = lag_deck(d)["bright_e"] * Q
    ppd = ppd_model(d, tg_channel(d))

    def excess(v):
        lag = model.lag_electrons(ppd, q, d.timing.t_tg, v)
        return lag["lag_e"] / lag["signal_e"] - 1e-3
    v_star = brentq(excess, 2.85, 3.0, xtol=1e-6)
    assert abs(v_close - v_star) <= 3e-3, (v_close, v_star)

    # the revision: the source's text with the rail replaced, and verify alone passes it
    text = out.read_text()
    assert "# A 4T pinned-photodiode pixel" in text and f'tg_high = "{r["knobs"][0]["value"]}"' in text
    code, stdout, err = cli("verify", out, "--out", tmp_path / "v", "--json")
    assert code == 0, err
    row, = json.loads(stdout)["rows"]
    assert row["status"] == "pass" and row["margin"] >= 0


def test_close_refuses_what_a_role_design_cannot_do(tmp_path):
    """Refused when the file loads (naming the field; exit 2 on the command line): an objective the family
    cannot evaluate, a key the design file lacks, a knob in a table the specs' measurement reads."""
    import shutil
    from pixelkit.errors import ConfigError
    from pixelkit.family import load_family_design
    spec = {"image_lag": {"max": "0.1 %"}}
    knobs = {"levels.tg_high": ["2.9 V", "3.3 V"]}
    for close, field in (({"objective": "max full_well_primary", "knobs": knobs}, "close.objective"),
                         ({"objective": "min power", "knobs": {"pixel.sf_bias": ["1 uA", "2 uA"]}},
                          "close.knobs.pixel.sf_bias"),
                         ({"objective": "min power", "knobs": {"experiment.t_window": ["10 us", "30 us"]}},
                          "close.knobs.experiment.t_window")):
        with pytest.raises(ConfigError) as e:
            load_family_design(_design(tmp_path, "3.3 V", spec, close), "pixel4t")
        assert e.value.field == field
    p = _design(tmp_path, "3.3 V", spec, {"objective": "min area", "knobs": knobs})
    assert load_family_design(p, "pixel4t").close.goal == ("min", "area")
    # the netlist family has no devices of its own: no gate area to minimise
    shutil.copytree(ROOT / "designs" / "pixel4t_netlist", tmp_path / "pixel4t_netlist")
    q = tmp_path / "net.toml"
    q.write_text((ROOT / "designs" / "pixel4t_netlist.toml").read_text() + "\n" + to_toml(
        {"close": {"objective": "min area", "knobs": {"column.bias": ["1 uA", "3 uA"]}}}))
    with pytest.raises(ConfigError) as e:
        load_family_design(q, "netlist")
    assert e.value.field == "close.objective" and "area" not in e.value.allowed.split("(")[0]
    # a candidate of a netlist pixel is its file with the knob changed, loaded where the file is (its netlist
    # resolves beside it)
    from pixelkit.sweep.space import design_with
    q.write_text((ROOT / "designs" / "pixel4t_netlist.toml").read_text())
    d = load_family_design(q, "netlist")
    c = design_with(d, {"column.bias": "1.5 uA"})
    assert c.column.bias == pytest.approx(1.5e-6, rel=1e-12) and c.source == str(q) and c.cell().subckt == d.cell().subckt
