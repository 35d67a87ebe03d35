"""The reference design as it was before its read was retimed for settling (issue 27), as text."""
import re

from conftest import REF


def untimed() -> str:
    """The reference design's text without its [primary.timing] / [secondary.timing] tables."""
    out, skip = [], False
    for line in REF.read_text().splitlines(keepends=True):
        if line.startswith("["):
            skip = line.split("]")[0] in ("[primary.timing", "[secondary.timing")
        if not skip:
            out.append(line)
    return "".join(out)


def former() -> str:
    """400 nA load and the default read: the former reference design."""
    text = re.sub(r'^sf_bias = "1 uA".*$', 'sf_bias = "400 nA"', untimed(), flags=re.M)
    assert "400 nA" in text and ".timing]" not in text
    return text
