"""The light map's verdict: each column's AFE output error against a limit.

This module judges; it does not model light. Its input is what ``layout.pex.light.light_map``
measured (per column: the output error and the read noise there), whatever model gave the
junctions' currents (the geometric exposure today; a collection model by wavelength later,
issue 48): a change there changes the numbers judged, not the rule.

The limit is either a multiple of the read noise at the AFE (``"1x"``, the default: light that
reaches the readout may add no more to a frame than one read noise, the level at which it is
visible in a single frame) or a voltage (``"2 mV"``). It is the design's, as a spec's limit is:
``[light] max_readout_error`` of the revision's file (default ``"1x"``), which ``pixelkit
lightmap``, the report's light-map section and the datasheet judge against; ``lightmap
--max-error`` overrides it for one run. Exit as every verdict command
(``errors.verdict_exit``): 1 when a column's error is beyond the limit, 0 when every column is
within it.
"""
from __future__ import annotations

import re

from ..errors import ConfigError, verdict_exit

DEFAULT = "1x"


def parse_limit(text: str, source: str = "lightmap", field: str = "--max-error") -> tuple[str, float]:
    """("noise", k) for ``"k x"``, ("V", volts) for a voltage; ConfigError naming ``field`` of ``source``
    (the option, or the design's ``light.max_readout_error``)."""
    from ..units import quantity
    t = str(text).strip()
    m = re.fullmatch(r"([0-9.eE+-]+)\s*x", t)
    try:
        if m:
            k = float(m.group(1))
            kind, value = "noise", k
        else:
            kind, value = "V", quantity(t, "V", field, source)
    except (ValueError, ConfigError):
        kind, value = None, None
    if kind is None or not (0 < value < (1e4 if kind == "noise" else 10.0)):
        raise ConfigError(source, field, text, "a multiple of the read noise at the AFE ('1x', "
                          "'0.5x': above 0, below 1e4) or a voltage ('2 mV': above 0, below 10 V)")
    return kind, value


def judge(columns: dict, limit: str = DEFAULT) -> dict:
    """The verdict on ``columns`` ({column: {"error_V", "read_noise_V", ...}}, as the light map gives
    them) against ``limit``."""
    kind, value = parse_limit(limit)
    out = {}
    for c, v in columns.items():
        lim = value * v["read_noise_V"] if kind == "noise" else value
        err = abs(v["error_V"])
        out[c] = {"error_V": v["error_V"], "limit_V": lim, "margin_V": lim - err,
                  "status": "pass" if err <= lim else "fail"}
    failed = [c for c, v in out.items() if v["status"] == "fail"]
    code = verdict_exit([v["status"] for v in out.values()])   # no column measured: 5, never a pass
    return {"limit": limit, "limit_kind": "x read noise" if kind == "noise" else "V", "columns": out,
            "failed": failed, "verdict": {0: "PASS", 1: "FAIL", 4: "SIMULATION FAILED", 5: "NOT MEASURED"}[code],
            "exit": code}
