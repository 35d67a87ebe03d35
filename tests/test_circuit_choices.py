"""Circuit choices a design file makes (issue 40, point 3): the boosted gate rail of the EC / TG / RST
switches and the transistor OTA's bias and compensation.

Independent paths: the switch physics (an NMOS passes a drain level only while its gate stays a
threshold, with body effect, above it: a gate that follows a -10 % supply soft-resets a 2.0 V FD
at a slow corner, a regulated gate does not), the frame's own lag measurement (a dark frame after
a saturated one) as the observable, and for the OTA the supply current its mirrors set (7 x the
reference: 1 + 2 + 4) against the power deck's SPICE currents.
"""
from dataclasses import replace

import pytest

from conftest import REF, run_cli
from pixelkit.verify import conditions, measure


def _at(design, corner, temp_c, supply):
    return conditions.at(design, conditions.Condition(corner, temp_c + 273.15, supply))


def _boosted(design, v_gate=3.3):
    return replace(design, pixel=replace(design.pixel, gate_drive="boosted", v_gate=v_gate))


def test_boosted_gates_keep_the_reset_hard_at_a_low_supply(ref_design):
    """ss 27 degC at -10 % supply (2.97 V): gates that follow the supply end the 2.0 V FD reset in
    subthreshold (threshold ~1.1 V with body effect at ss: 2.97 - 1.1 < 2.0), so a dark frame after
    a saturated one keeps part of it (lag of several %); the same pixel with its gates on a regulated
    3.3 V rail resets hard (lag below the 0.1 % spec). RS stays on the supply."""
    soft = measure.figures({"lag": measure.lag(_at(ref_design, "ss", 27.0, -0.1))})
    hard = measure.figures({"lag": measure.lag(_at(_boosted(ref_design), "ss", 27.0, -0.1))})
    assert soft["image_lag_primary"] > 0.01
    assert hard["image_lag_primary"] < 0.001
    from pixelkit.circuits.testbench import controls, timings
    d = _at(_boosted(ref_design), "ss", 27.0, -0.1)
    levels = {e.name: max(v for _, v in e.value.points) for e in controls(d, timings(d, 16e-6), 1, False)}
    assert levels["Vec_p"] == levels["Vtg_s"] == levels["Vrst_p"] == 3.3
    assert levels["Vrs_p"] == pytest.approx(0.9 * 3.3)


@pytest.mark.parametrize("edit, field, words", [
    ('gate_drive = "boosted"', "pixel.v_gate", "a gate level with gate_drive"),
    ('gate_drive = "boosted"\nv_gate = "3.9 V"', "pixel.v_gate", "rated 3.63 V"),
    ('v_gate = "3.3 V"', "pixel.v_gate", 'gate_drive = "supply"'),
    ('gate_drive = "pmos"', "pixel.gate_drive", "supply"),
])
def test_gate_rail_refusals_name_the_field(tmp_path, edit, field, words):
    text = REF.read_text().replace('v_fd_reset = "2.0 V"', 'v_fd_reset = "2.0 V"\n' + edit, 1)
    (tmp_path / "d.toml").write_text(text)
    code, out, err = run_cli("models", tmp_path / "d.toml")
    assert code == 2 and field in err and words in err, err


def test_ota_supply_current_is_seven_times_its_reference(ref_design):
    """The OTA's AFE block in SPICE against its mirrors (reference 1, tail 2, output stage 4: 7 x
    ``afe.ota_bias``) at 1 uA; the block scales with the reference (a tenth of it at a tenth)."""
    d = replace(ref_design, afe=replace(ref_design.afe, opamp="ota", ota_bias=1e-6, ota_cc=0.25e-12, ota_rz=20e3))
    p = measure.power(d)
    cols = d.primary.cols + d.secondary.cols
    assert p["estimate"]["chip_blocks_W"]["afe"] == pytest.approx(7 * 1e-6 * 3.3 * cols, rel=1e-9)
    assert p["chip_blocks_W"]["afe"] == pytest.approx(p["estimate"]["chip_blocks_W"]["afe"], rel=0.15)
