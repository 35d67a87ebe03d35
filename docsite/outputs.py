"""A command's output as a page shows it, checked against what the command prints now.

A page shows what a command prints in a ```text block right after the ```sh block that runs it
(the README's tour, the tutorial, the how-to guides). ``tests/test_tutorial.py`` runs those
blocks; after each one it holds the page's text block against the block's output (stdout and
stderr) with :func:`compare`:

- every line of the page's block must be a line of the output, in order (lines may be left out,
  ``...`` marks a cut, and a line ending in ``...`` is the start of a longer line): the same
  words once each number is taken out and runs of spaces count as one (a column that widened
  still matches);
- every number of that line must be the output's at the digits the page quotes (``1035.1``
  stands for 1035.05 - 1035.15), so a figure that moved fails the test naming the page, the line
  and the number now printed;
- a line that differs from run to run (the run count served from the cache, a wall time) is
  named by an HTML comment right above the text block, ``<!-- vary: REGEX -->``: its words are
  checked, its numbers are not. The kit's ``N SPICE runs (M from cache) in T s`` line is such a
  line on every page, as is a line ending in a wall time (:data:`VARY`); a wall time inside a
  line (``KLayout 0.28.5, 8.7 s): 4 violation(s)``) is left out, the line's other numbers not.

:func:`compare` also returns the block rewritten from the output (each line that moved replaced
by the output's line as printed): ``PIXELKIT_DOCS_REWRITE=1`` on the test run writes it into the
page instead of failing (docs/howto-docs-figures.md).
"""
from __future__ import annotations

import re

from docsite.figures import _digits as _half_unit

NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
#: lines whose numbers differ from run to run on every page: the cache's share and wall times
VARY = (r"SPICE runs? \(\d+ from cache\)", r"\bin \d+(?:\.\d+)? (?:s|min)\b", r"\b\d+(?:\.\d+)? (?:s|min)$")
CUT = {"...", "…"}


def skeleton(line: str) -> str:
    """The line's words: numbers taken out, runs of white space as one."""
    return " ".join(NUMBER.sub("#", line).split())


def numbers_agree(quoted: str, printed: str) -> bool:
    """``quoted`` is ``printed`` at the digits the page quotes (or the kit prints, the coarser)."""
    try:
        q, v = float(quoted), float(printed)
    except ValueError:
        return quoted == printed
    return abs(q - v) <= max(_half_unit(quoted), _half_unit(printed)) * (1 + 1e-9)


#: a wall time inside a line ("KLayout 0.28.5, 8.7 s): 4 violation(s)"): not compared, the rest is
WALL = re.compile(r" (?:s|min)(?=[),:;]|$)")


def _same_numbers(doc: str, out: str) -> list[tuple[str, str]]:
    """[(quoted, printed)] of the numbers that differ between two lines of the same skeleton (wall
    times left out)."""
    return [(q.group(0), v.group(0)) for q, v in zip(NUMBER.finditer(doc), NUMBER.finditer(out))
            if not WALL.match(doc, q.end()) and not numbers_agree(q.group(0), v.group(0))]


def _cut_like(line: str, out: str) -> str:
    """``out`` cut after as many numbers as ``line`` (whose tail is cut, ``...``) holds."""
    n = len(NUMBER.findall(line.rstrip()[:-3]))
    ends = [m.end() for m in NUMBER.finditer(out)][:n]
    keep = len(line.rstrip()[:-3]) if not ends else max(ends[-1], len(line.rstrip()) - 3)
    return out[:keep].rstrip() + " ..."


def compare(doc: str, output: str, vary=()) -> tuple[list[str], str]:
    """([what does not match, one sentence each], the page's block rewritten from ``output``).

    ``doc`` is the page's text block, ``output`` what the command printed, ``vary`` regular
    expressions of lines whose numbers are not compared (besides :data:`VARY`)."""
    vary = [re.compile(v) for v in (*VARY, *vary)]
    out_lines = output.splitlines()
    skel = [skeleton(o) for o in out_lines]
    problems, new, pos = [], [], 0
    for line in doc.splitlines():
        if line.strip() in CUT or not line.strip():
            new.append(line)
            continue
        s = skeleton(line)
        if line.rstrip().endswith("...") and line.strip() not in CUT:   # the line's tail cut
            s = skeleton(line.rstrip()[:-3])
            found = [j for j in range(pos, len(out_lines)) if skel[j].startswith(s)]
        else:
            found = [j for j in range(pos, len(out_lines)) if skel[j] == s]
        if not found:
            problems.append(f"not printed (any more): {line.strip()!r}")
            new.append(line)
            continue
        varies = any(v.search(line) for v in vary)
        j = next((j for j in found if varies or not _same_numbers(line, out_lines[j])), found[0])
        pos = j + 1
        moved = [] if varies else _same_numbers(line, out_lines[j])
        if moved:
            problems.append(f"{line.strip()!r}: now {out_lines[j].strip()!r} ("
                            + ", ".join(f"{q} -> {v}" for q, v in moved) + ")")
            new.append(out_lines[j].rstrip() if not line.rstrip().endswith("...")
                       else _cut_like(line, out_lines[j]))
        else:
            new.append(line)
    return problems, "\n".join(new)
