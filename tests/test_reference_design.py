"""The comparison with [Thesis2019] is made for its test chip only.

Independent path: the values the dissertation prints (table 3.2, chapter 3, appendix A),
written here from the document, not from the code's table; a design that differs from the
chip in one stated value is not the reference, and its ``simulate`` text does not set the
dissertation's currents beside its own.
"""
from dataclasses import replace

from pixelkit.experiments.reference import departures, differences, is_reference
from pixelkit.report.text import simulate_text


def test_the_thesis_read_is_the_thesis_chip(thesis_read_design):
    """designs/dual_pixel_revA_thesis_read.toml: the chip at every value the dissertation states."""
    d = thesis_read_design
    assert is_reference(d), differences(d)
    p, s = d.primary, d.secondary
    assert (p.rows, p.cols, s.rows, s.cols) == (27, 50, 27, 150)                  # table 3.2
    assert round(p.pd_width * 1e6, 2) == 15.1 and round(p.pd_height * 1e6, 2) == 13.55
    assert round(d.pixel.sf_bias * 1e9, 6) == 400 and not departures(d)


def test_the_reference_is_the_chip_with_its_departure_named(ref_design):
    """designs/dual_pixel_revA.toml (issue 27): the chip with a 1 uA load, named as a departure."""
    assert is_reference(ref_design)
    assert [x.split(":")[0] for x in departures(ref_design)] == ["pixel.sf_bias 1e-06"]


def test_one_stated_value_changed_is_another_design(ref_design):
    other = replace(ref_design, pixel=replace(ref_design.pixel, sf_bias=500e-9))
    assert not is_reference(other) and differences(other) == ["pixel.sf_bias 5e-07"]
    devices = replace(ref_design.pixel.devices, sf_w=2e-6)  # the thesis prints no device sizes
    assert is_reference(replace(ref_design, pixel=replace(ref_design.pixel, devices=devices)))


def test_simulate_sets_the_thesis_currents_beside_the_reference_only(experiment):
    assert "thesis 1400 / 52 = 26.9" in simulate_text(experiment, reference=True)
    assert "thesis" not in simulate_text(experiment, reference=False)
