"""The time-stepped exposure engine that every frame-level check relies on.

Independent path: exact integrals of simple cases (a static rectangle gives its
covered area x time; a rectangle of width W crossing a pixel at speed v gives
W / v of full coverage, whatever the aperture; a weighted window scales).
"""
import numpy as np
import pytest

from pixelkit.errors import PixelkitError
from pixelkit.sensor.exposure import Cells, Rect, expose, step_for


def test_static_rectangle_area_times_time():
    r = [Rect(0.5, 1.25, 3.0, 2.5, irradiance=2.0)]
    rows, cols = Cells.grid(6), Cells.grid(6)
    img = expose(r, rows, cols, np.tile([[1.0, 4.0]], (6, 1)), step_for(r, rows, cols))
    assert img.sum() == pytest.approx(2.0 * 3.0 * 2.5 * 3.0)
    assert img[2, 2] == pytest.approx(6.0) and img[1, 0] == pytest.approx(2.0 * 0.5 * 0.75 * 3.0)


@pytest.mark.parametrize("aperture", [1.0, 0.2])
def test_crossing_rectangle_dwell_time(aperture):
    v, width = 0.37, 4.0
    r = [Rect(-10.0, 0.0, width, 1.0, vx=v)]
    rows, cols = Cells.grid(1), Cells.grid(12, aperture=aperture)
    img = expose(r, rows, cols, np.array([[0.0, 60.0]]), step_for(r, rows, cols))
    assert img[0, 3] == pytest.approx(width / v, rel=1e-3)


def test_weighted_windows_add():
    r = [Rect(0.0, 0.0, 2.0, 2.0)]
    rows, cols = Cells.grid(2), Cells.grid(2)
    w = np.tile([[[0.0, 1.0, 1.0], [1.0, 11.0, 0.01]]], (2, 1, 1))
    assert expose(r, rows, cols, w, step_for(r, rows, cols))[0, 0] == pytest.approx(1.1)


def test_bad_inputs_are_clear():
    with pytest.raises(PixelkitError, match="aperture"):
        Cells.grid(4, 1.0, aperture=2.0)
    with pytest.raises(PixelkitError, match="windows must have shape"):
        expose([Rect(0, 0, 1, 1)], Cells.grid(3), Cells.grid(3), np.zeros((2, 2)), 0.1)
