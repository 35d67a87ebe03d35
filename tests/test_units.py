import math

import pytest

from pixelkit.errors import ConfigError
from pixelkit.units import quantity


@pytest.mark.parametrize("text,dim,si", [
    ("15.1 um", "m", 15.1e-6), ("26.54 fF", "F", 26.54e-15), ("0.64 um2", "m2", 0.64e-12),
    ("0.64 um^2", "m2", 0.64e-12), ("500 kHz", "Hz", 5e5), ("400 nA", "A", 4e-7),
    ("1.17 uW/um2", "W/m2", 1.17e6), ("0.1 fF/um2", "F/m2", 1e-4), ("0.3 fF/um", "F/m", 3e-10),
    ("27 degC", "K", 300.15), ("300 K", "K", 300.0), ("60 km/h", "m/s", 60 / 3.6),
    ("1 nA/cm2", "A/m2", 1e-5), ("60 dB", "1", 1000.0), (0.5, "1", 0.5), ("7.4 deg", "rad", math.radians(7.4)),
])
def test_parses_to_si(text, dim, si):
    assert quantity(text, dim, "f") == pytest.approx(si, rel=1e-12)


@pytest.mark.parametrize("text,dim,needle", [
    ("15.1", "m", "with a unit"), (15.1, "m", "with a unit"), ("15.1 pF", "m", "in m"),
    ("abc", "V", "with a unit"), ("1 furlong", "m", "known unit"), ("nan V", "V", "with a unit"),
    ("1e999 V", "V", "finite"), (True, "1", "quantity"),
])
def test_refuses_with_the_field_named(text, dim, needle):
    with pytest.raises(ConfigError) as e:
        quantity(text, dim, "primary.pd_width", "x.toml")
    assert "primary.pd_width" in str(e.value) and needle in str(e.value)
