"""Where a failed transient went wrong, in the circuit's own terms.

ngspice names the node whose step it could not shrink ("trouble with node
vrs_s#branch"): often a node of the other array, or a source branch, not the
junction that caused it. When a transient stops at a time, the deck is run again
up to just before that time with every node saved, and the node furthest below
ground (a forward-biased junction: a photodiode, a storage node or a column line
of an over-exposed pixel) is named with its array. It costs one more run of the
failed deck, and only when a deck has failed for good.
"""
from __future__ import annotations

import re
from dataclasses import replace

#: A node this far below ground is a forward-biased junction.
FORWARD_V = -0.1
_TIME = re.compile(r"time\s*=\s*([0-9.eE+-]+)")


def array_of(node: str) -> str:
    """``primary`` / ``secondary`` / ``""`` from the kit's node names (``x1.xp.pd``, ``xs_0_3.fd``,
    ``col_p_0``, ``in_col_s_2``, ``rs_s#branch``, ...)."""
    side = {"p": "primary", "s": "secondary"}
    for part in node.lower().split("."):
        m = re.fullmatch(r"x(p|s)\d*(?:_\d+_\d+)?", part)
        if m:
            return side[m.group(1)]
    m = re.search(r"col_(p|s)", node.lower()) or re.search(r"_(p|s)(?:_\d+)?(?:#branch)?$", node.lower())
    return side[m.group(1)] if m else ""


def locate(deck, message: str, run) -> str:
    """One sentence naming the most forward-biased node just before the failure, or ``""``.
    ``run(deck)``: a Result of ``deck`` or None (the engine's runner)."""
    m = _TIME.search(message or "")
    if deck.analysis is None or deck.analysis.kind != "tran" or not m:
        return ""
    t_fail = float(m.group(1))
    if not 0 < t_fail <= deck.analysis.stop:
        return ""
    probe = replace(deck, analysis=replace(deck.analysis, stop=t_fail * (1 - 1e-4)), saves=(),
                    title=f"{deck.title}_site")
    try:
        res = run(probe)
    except Exception:  # noqa: BLE001 - a diagnosis never hides the failure it explains
        return ""
    if res is None:
        return ""
    low = []
    for name in res.names():
        if not name.startswith("v(") or "#" in name:
            continue
        v = float(res[name][-1])
        if v < FORWARD_V:
            low.append((v, name[2:-1]))
    if not low:
        return ""
    v, node = min(low)
    arr = array_of(node)
    return (f"just before it stopped (t = {t_fail * 1e6:.4g} us) the {arr + ' ' if arr else ''}node {node} was "
            f"at {v:.3g} V: a junction forward-biased (an over-exposed pixel?)")
