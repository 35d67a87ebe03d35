"""The thesis's read, which does not settle with the AFE attached (issue 27), as text.

designs/dual_pixel_revA_thesis_read.toml is the chip of [Thesis2019] with the ~400 nA load of its
simulations and the kit's default read (no timing keys); the reference, designs/dual_pixel_revA.toml, is
the same chip with the read that settles."""
from conftest import THESIS_READ


def untimed() -> str:
    """The thesis read's text: a design without [primary.timing] / [secondary.timing] tables."""
    text = THESIS_READ.read_text()
    assert ".timing]" not in text
    return text


def former() -> str:
    """400 nA load and the default read: the thesis's read, which does not settle."""
    text = untimed()
    assert 'sf_bias = "400 nA"' in text
    return text
