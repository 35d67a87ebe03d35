"""Refusing a result that holds a non-finite number before it is printed.

A figure that came out as NaN or infinity (a junction capacitance pushed to
``Infinity`` full well, a ratio over a zero swing) is not a result: printing it
would be a wrong number with exit 0, and ``Infinity`` is not even valid JSON.
:func:`refuse_nonfinite` names the first such figure by its path in the result.
"""
from __future__ import annotations

import math

from .errors import PixelkitError


def first_nonfinite(data, path: str = ""):
    """``(path, value)`` of the first NaN/inf number in nested dicts/lists/arrays, else None."""
    import numpy as np
    if isinstance(data, dict):
        for k, v in data.items():
            hit = first_nonfinite(v, f"{path}.{k}" if path else str(k))
            if hit:
                return hit
    elif isinstance(data, (list, tuple)):
        for i, v in enumerate(data):
            hit = first_nonfinite(v, f"{path}[{i}]")
            if hit:
                return hit
    elif isinstance(data, np.ndarray) and data.dtype.kind in "fc":
        bad = np.flatnonzero(~np.isfinite(data.ravel()))
        if bad.size:
            return f"{path}[{int(bad[0])}]", data.ravel()[bad[0]].item()
    elif isinstance(data, (float, np.floating)) and not math.isfinite(float(data)):
        return path, float(data)
    return None


def refuse_nonfinite(data) -> None:
    hit = first_nonfinite(data)
    if hit:
        raise PixelkitError(f"the result holds a non-finite figure, {hit[0]} = {hit[1]}: not printed "
                            "(the design's values are outside what the models can evaluate)")
