"""The reference design's read, which does not settle with the AFE attached (issue 27), as text.

The reference (designs/dual_pixel_revA.toml) keeps the ~400 nA load of [Thesis2019] and the kit's default
read; designs/dual_pixel_revA_settled.toml is the same chip with the read that settles."""
from conftest import REF


def untimed() -> str:
    """The reference design's text without [primary.timing] / [secondary.timing] tables."""
    out, skip = [], False
    for line in REF.read_text().splitlines(keepends=True):
        if line.startswith("["):
            skip = line.split("]")[0] in ("[primary.timing", "[secondary.timing")
        if not skip:
            out.append(line)
    return "".join(out)


def former() -> str:
    """400 nA load and the default read: the reference design's own read, which does not settle."""
    text = untimed()
    assert 'sf_bias = "400 nA"' in text and ".timing]" not in text
    return text
