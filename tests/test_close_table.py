"""The [close] table: every bad table refused with exit 2 naming the field and what is allowed, before
any simulation (the knob no spec depends on through the simulations: at close's first sensitivity
step, from cached decks); the knob space's written values read back as the design file holds them."""
import copy
import json
import math
import tomllib

import pytest

from conftest import REF, run_cli
from pixelkit.design import load_design
from pixelkit.errors import ConfigError
from pixelkit.schema import to_toml

BASE = tomllib.loads(REF.read_text())
AFE_SPEC = {"afe_gain_error": {"max": "0.5 %"}}
ONE = {"corners": ["tt"], "temperatures": ["27 degC"], "supplies": ["0 %"], "mc": 0}


def _write(tmp_path, close, spec=AFE_SPEC, verify=ONE, name="d.toml"):
    raw = copy.deepcopy(BASE)
    raw["spec"], raw["verify"] = spec, verify
    raw.pop("close", None)      # the reference's own [close] table (its revB's knobs)
    if close is not None:
        raw["close"] = close
    p = tmp_path / name
    p.write_text(to_toml(raw))
    return p


def knob(key, lo, hi, **kw):
    return {"objective": "min power", "knobs": {key: {"min": lo, "max": hi, **kw}}}


BAD = [  # (what, [close] table, field named, words of what is allowed)
    ("unknown key in [close]", {"objective": "min power", "knobs": {"afe.gain": ["100 V/V", "1000 V/V"]},
                                "budget": 3}, "close.budget", "no such field"),
    ("unknown key in a knob", knob("afe.gain", "100 V/V", "1000 V/V", start="200 V/V"), "close.knobs.afe.gain.start",
     "no such field"),
    ("not a design key", knob("pixel.frobnicate", "1 V", "2 V"), "close.knobs.pixel.frobnicate",
     "a numeric key of the design file"),
    ("inverted bounds", knob("pixel.sf_bias", "1.5 uA", "600 nA"), "close.knobs.pixel.sf_bias.max",
     "a bound above min"),
    ("equal bounds", knob("pixel.sf_bias", "1 uA", "1000 nA"), "close.knobs.pixel.sf_bias.max", "a bound above min"),
    ("non-numeric bound", knob("pixel.sf_bias", "lots", "1 uA"), "close.knobs.pixel.sf_bias.min",
     "a number with a unit"),
    ("bound of another unit", knob("pixel.sf_bias", "1 V", "2 V"), "close.knobs.pixel.sf_bias.min",
     "a quantity in A"),
    ("infinite bound", knob("afe.gain", 100.0, math.inf), "close.knobs.afe.gain.max", "a quantity with its unit"),
    ("infinite bound as text", knob("pixel.sf_bias", "600 nA", "1e999 A"), "close.knobs.pixel.sf_bias.max",
     "a finite value"),
    ("missing bound", {"objective": "min power", "knobs": {"pixel.sf_bias": {"min": "600 nA"}}},
     "close.knobs.pixel.sf_bias.max", "both min and max"),
    ("bound the design file refuses", knob("pixel.sf_bias", "600 nA", "5 mA"), "close.knobs.pixel.sf_bias.max",
     "a value <= 1 mA"),
    ("log scale through zero", knob("pixel.v_fd_reset", "0 V", "2 V", scale="log"),
     "close.knobs.pixel.v_fd_reset.min", "a value > 0"),
    ("step larger than the span", knob("pixel.devices.rst_w", "0.5 um", "0.6 um", step="0.2 um"),
     "close.knobs.pixel.devices.rst_w.step", "below the span"),
    ("a whole number", knob("primary.rows", 10, 40), "close.knobs.primary.rows", "does not choose whole numbers"),
    ("a text key", knob("afe.opamp", "1", "2"), "close.knobs.afe.opamp", "a numeric key"),
    ("fixed by the grid: temperature", knob("temperature", "20 degC", "30 degC"), "close.knobs.temperature",
     "fixed by the sign-off grid"),
    ("fixed by the spec: a spec's limit", knob("spec.afe_gain_error.max", "0.1 %", "1 %"),
     "close.knobs.spec.afe_gain_error.max", "the specs are what close must meet"),
    ("fixed by the spec: the sign-off grid", knob("verify.min_yield", "0.5", "0.9"), "close.knobs.verify.min_yield",
     "sign-off grid"),
    ("fixed by the spec: how a figure is measured", knob("experiment.mid_fraction", "0.4", "0.6"),
     "close.knobs.experiment.mid_fraction", "moves the measurement, not the chip"),
    ("no spec reads it", knob("scene.distance", "3 m", "9 m"), "close.knobs.scene.distance", "no measurement of "
     "pixelkit verify reads [scene]"),
    ("a choice the key does not have", {"objective": "min power", "knobs": {"pixel.gate_drive": {
        "choices": ["supply", "charge_pump"]}}}, "close.knobs.pixel.gate_drive.choices[1]", "one of supply, boosted"),
    ("choices of a numeric key", {"objective": "min power", "knobs": {"pixel.sf_bias": {"choices": ["1 uA", "2 uA"]}}},
     "close.knobs.pixel.sf_bias.choices", "a text key with a fixed set of values"),
    ("bounds on a choice", {"objective": "min power", "knobs": {"pixel.gate_drive": {
        "choices": ["supply", "boosted"], "min": "1 V"}}}, "close.knobs.pixel.gate_drive.min", "no bounds on a knob "
     "with choices"),
    ("a free-text key as a choice", {"objective": "min power", "knobs": {"revision": {"choices": ["B", "C"]}}},
     "close.knobs.revision.choices", "a text key with a fixed set of values"),
    ("an objective on a choice", {"objective": "max pixel.gate_drive", "knobs": {"pixel.gate_drive": {
        "choices": ["supply", "boosted"]}}}, "close.objective", "a figure"),
    ("no knob", {"objective": "min power", "knobs": {}}, "close.knobs", "at least one knob"),
    ("objective without a sense", {"objective": "power", "knobs": {"afe.gain": ["100 V/V", "1000 V/V"]}},
     "close.objective", "\"min X\" or \"max X\""),
    ("objective nobody measures", {"objective": "max beauty", "knobs": {"afe.gain": ["100 V/V", "1000 V/V"]}},
     "close.objective", "a figure"),
    ("a list of three", {"objective": "min power", "knobs": {"afe.gain": ["100 V/V", "1000 V/V", "2000 V/V"]}},
     "close.knobs.afe.gain", "a list of two values"),
    ("a bad key", {"objective": "min power", "knobs": {"afe..gain": ["100 V/V", "1000 V/V"]}}, "close.knobs.afe..gain",
     "a dotted key"),
    ("tied to itself", knob("afe.c11", "150 fF", "600 fF", tied=["afe.c11"]), "close.knobs.afe.c11.tied[0]",
     "another design key"),
    ("tied to another unit", knob("afe.c11", "150 fF", "600 fF", tied=["afe.ota_bias"]),
     "close.knobs.afe.c11.tied[0]", "same unit as afe.c11"),
    ("tied to no key", knob("afe.c11", "150 fF", "600 fF", tied=["afe.c99"]), "close.knobs.afe.c11.tied[0]",
     "a numeric key of the design file"),
    ("tied to a knob", {"objective": "min power", "knobs": {"afe.c11": {"min": "150 fF", "max": "600 fF",
                                                                        "tied": ["afe.c13"]},
                                                            "afe.c13": ["150 fF", "600 fF"]}},
     "close.knobs.afe.c11.tied[0]", "no other knob"),
    ("tied on a choice", {"objective": "min power", "knobs": {"pixel.gate_drive": {
        "choices": ["supply", "boosted"], "tied": ["afe.opamp"]}}}, "close.knobs.pixel.gate_drive.tied",
     "no bounds on a knob with choices"),
]


@pytest.mark.parametrize("what,close,field,allowed", BAD, ids=[b[0] for b in BAD])
def test_bad_close_table_is_refused_at_load(tmp_path, what, close, field, allowed):
    with pytest.raises(ConfigError) as err:
        load_design(_write(tmp_path, close))
    assert err.value.field == field, str(err.value)
    assert allowed in err.value.allowed, str(err.value)


def test_knob_keys_quoted_or_nested_read_the_same(tmp_path):
    quoted = _write(tmp_path, {"objective": "max pixel.v_fd_reset",
                               "knobs": {"pixel.v_fd_reset": ["1.6 V", "2.2 V"],
                                         "pixel.devices.rst_w": {"min": "0.42 um", "max": "2 um", "step": "5 nm"}}})
    nested = tmp_path / "n.toml"
    nested.write_text(quoted.read_text().split("[close]")[0] + "[close]\nobjective = \"max pixel.v_fd_reset\"\n"
                      "[close.knobs]\npixel.v_fd_reset = [\"1.6 V\", \"2.2 V\"]\n"
                      "pixel.devices.rst_w = { min = \"0.42 um\", max = \"2 um\", step = \"5 nm\" }\n")
    a, b = load_design(quoted).close, load_design(nested).close
    assert [(k.name, k.lo, k.hi, k.grid, k.log) for k in a.knobs] == [(k.name, k.lo, k.hi, k.grid, k.log)
                                                                        for k in b.knobs]
    got = {k.name: (k.lo, k.hi, k.grid, k.log) for k in a.knobs}
    assert got["pixel.v_fd_reset"] == (1.6, 2.2, None, False)      # 2.2 / 1.6 < 3: lin
    assert got["pixel.devices.rst_w"][3] is True                    # 2 / 0.42 >= 3: log
    assert got["pixel.devices.rst_w"][2] == pytest.approx(5e-9)


def test_knob_values_are_written_as_the_design_file_reads_them(ref_design):
    """Every value the knob space writes loads back (through the unit parser, not the writer) to the
    value close simulates, rounded to the knob's step when it has one."""
    from pixelkit.close.knobs import Space
    from pixelkit.verify.close_table import Knob
    from pixelkit.units import quantity
    knobs = (Knob(name="pixel.sf_bias", lo=6e-7, hi=1.5e-6, dim="A", scale="log"),
             Knob(name="pixel.devices.rst_w", lo=0.42e-6, hi=2e-6, dim="m", grid=5e-9),
             Knob(name="afe.gain", lo=100.0, hi=1e4, dim="1", unit_required=True),
             Knob(name="secondary.mask_opening", lo=0.1e-12, hi=4e-12, dim="m2"))
    space = Space(knobs)
    x = space.snap([1.23456789e-6, 0.6041e-6, 398.16666, 0.64321e-12])
    texts = space.texts(x)
    assert texts[1] == "0.605 um" and texts[0] == "1.23457 uA" and texts[2].endswith("V/V")
    for k, t, v in zip(knobs, texts, x):
        assert quantity(t, k.dim, k.name) == v
    assert space.to_x(space.to_u(x)) == pytest.approx(x, rel=1e-12)
    assert space.snap([1e-9, 5e-6, 1e9, 1e-15]) == pytest.approx([6e-7, 2e-6, 1e4, 1e-13], rel=1e-12)  # clipped


def test_bound_that_breaks_the_design_at_a_supply_corner_exits_2(tmp_path, cli):
    """3.1 V is below the 3.3 V supply (the file loads) but above it at -10 %: refused naming the bound,
    before any simulation."""
    p = _write(tmp_path, {"objective": "min power", "knobs": {"afe.vref": ["2 V", "3.1 V"]}},
               verify={**ONE, "supplies": ["-10 %", "0 %"]})
    code, out, err = cli("close", p, "--out", tmp_path / "b.toml", "--json")
    assert code == 2, err
    e = json.loads(out)
    assert e["field"] == "close.knobs.afe.vref.max" and "afe.vref" in e["allowed"], e
    assert not (tmp_path / "b.toml").exists() and not (tmp_path / "b.close.json").exists()


def test_no_close_table_exits_2(tmp_path, cli):
    code, out, err = cli("close", _write(tmp_path, None), "--json")
    assert code == 2 and json.loads(out)["field"] == "close", out + err


def test_too_few_samples_for_min_yield_exits_2(tmp_path, cli):
    p = _write(tmp_path, {"objective": "min power", "knobs": {"afe.gain": ["100 V/V", "1000 V/V"]}},
               verify={**ONE, "mc": 20, "min_yield": "99 %"})
    code, out, err = cli("close", p, "--out", tmp_path / "b.toml", "--json")
    assert code == 2, err
    e = json.loads(out)
    assert e["field"] == "verify.mc" and "at least" in e["allowed"], e


def test_knob_no_spec_depends_on_exits_2(tmp_path, cli):
    """The column load's bias reaches no deck of the AFE bench, the only spec's: close's first sensitivity
    step finds every figure unchanged and refuses the knob (exit 2) without writing anything."""
    p = _write(tmp_path, {"objective": "min afe.gain", "knobs": {"afe.gain": ["100 V/V", "1000 V/V"],
                                                                 "pixel.sf_bias": ["600 nA", "1.5 uA"]}})
    code, out, err = cli("close", p, "--out", tmp_path / "b.toml", "--json")
    assert code == 2, err
    e = json.loads(out)
    assert e["field"] == "close.knobs.pixel.sf_bias" and "some spec depends on" in e["allowed"], e
    assert not (tmp_path / "b.toml").exists() and not (tmp_path / "b.close.json").exists()


def test_one_choice_is_the_designers_circuit_and_absent_knobs_start_mid_bounds():
    """The reference's own [close] table: ``afe.opamp = { choices = ["ota"] }`` is one circuit, the
    designer's (close solves under it, never the macromodel); under ``gate_drive = "boosted"`` the rail
    revA leaves absent starts at the middle of its bounds (as do the OTA's keys its file does not write),
    under ``"supply"`` it is left out."""
    from pixelkit.close.choices import _under
    d = load_design(REF)
    by = {k.name: k for k in d.close.knobs}
    assert by["afe.opamp"].choices == ("ota",) and by["pixel.gate_drive"].choices == ("boosted", "supply")
    numeric = [k for k in d.close.knobs if not k.choices]
    base, active, left = _under(d, {"pixel.gate_drive": "boosted", "afe.opamp": "ota"}, numeric)
    assert base.afe.opamp == "ota" and base.pixel.gate_drive == "boosted" and left == []
    assert base.pixel.v_gate == pytest.approx((3.3 + 3.63) / 2)
    # the OTA's keys revA's file does not write (it uses the macromodel) start mid-bounds too, not at
    # the schema's defaults (10 uA, 1 pF: outside the bounds or at one); those it writes start as written
    assert base.afe.ota_bias == pytest.approx(1.26491e-6, rel=1e-5) and base.afe.ota_cc == pytest.approx(
        math.sqrt(0.15e-12 * 1e-12), rel=1e-5) and base.afe.c11 == pytest.approx(500e-15)
    base, active, left = _under(d, {"pixel.gate_drive": "supply", "afe.opamp": "ota"}, numeric)
    assert left == ["pixel.v_gate"] and base.pixel.v_gate is None and base.afe.opamp == "ota"


def test_a_tied_key_takes_its_knobs_value_everywhere_close_writes():
    """The reference's C13 is tied to C11 (its AFE's gain C11 / C13 stays 1): every design close
    simulates and the revision it writes carry one value in both keys."""
    from pixelkit.close.knobs import Space
    d = load_design(REF)
    k = next(k for k in d.close.knobs if k.name == "afe.c11")
    assert k.tied == ("afe.c13",) and "afe.c13" not in {j.name for j in d.close.knobs}
    space = Space((k,))
    x = space.snap([320e-15])
    o = space.overrides(x)
    assert o == {"afe.c11": "320 fF", "afe.c13": "320 fF"}
    moved = space.design(d, x)
    assert moved.afe.c11 == moved.afe.c13 == pytest.approx(320e-15) and moved.afe.c12 == d.afe.c12
