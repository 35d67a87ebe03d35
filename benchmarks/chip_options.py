"""The whole chip's decks under other ngspice options: what each costs and how far it moves the figures.

    python3 benchmarks/chip_options.py [--rows 9] [--cols 2] [--only NAME,..] [--json] [DESIGN.toml]

A slice of the whole chip as ``pixelkit array DESIGN --rows R --cols C --afe`` simulates it (column
chains with the AFE, the settling reads, the default gradient scene), run once per option set in
this one process, each on a fresh empty simulation cache:

- ``kit`` (the baseline): the kit's options (``spice.options.DEFAULTS``: reltol 1e-5, abstol 1e-14,
  chgtol 1e-18, gmin 1e-15, gear);
- each candidate below, over the kit's options;
- ``converged``: reltol 1e-6, abstol 1e-12 (``chip.frame.CONVERGED``, what ``array --check`` takes
  as converged): the independent reference the error of each set is measured against.

Printed per set: ngspice's CPU seconds (every child process waited for), the decks, the ratio to
the baseline's CPU, and the largest difference over every subpixel of both arrays of the
double-sampled signal, the AFE output and the settling error, against the baseline and against the
converged run (mV). A set "keeps the numbers" when its difference from the baseline is at most
``KEEP_MV`` and its error against the converged run is no larger than the baseline's own.
"""
from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path

from common import child_cpu_s, chip_slice

#: How far an option set may move any figure from the kit's options: a tenth of the frame's own
#: error at the kit's tolerances against the converged deck (0.13 - 0.17 mV, docs/arrays.md).
KEEP_MV = 0.013
CANDIDATES = {
    "abstol 1e-12": (("abstol", 1e-12),),
    "chgtol 1e-16": (("chgtol", 1e-16),),
    "trtol 20": (("trtol", 20),),
    "trap": (("method", "trap"),),
}


def _frame(design, ph, options):
    from pixelkit.chip.frame import simulate_frame
    os.environ["PIXELKIT_CACHE"] = tempfile.mkdtemp(prefix="pk-bench-chipopt-")
    c0, t0 = child_cpu_s(), time.perf_counter()
    f = simulate_frame(design, ph.iph_p, ph.iph_s, with_afe=True, settling=True, compression=ph.compression,
                       options=options or None)
    return f, child_cpu_s() - c0, time.perf_counter() - t0


def _figures(f) -> dict:
    import numpy as np
    out = {}
    for k in ("primary", "secondary"):
        out[f"{k} signal"] = np.asarray(f.signal[k], float)
        out[f"{k} afe"] = np.asarray(f.afe[k], float)
        out[f"{k} settling"] = np.asarray(f.settling[k], float)
    return out


def _diff_mV(a: dict, b: dict) -> float:
    import numpy as np
    return float(max(np.nanmax(np.abs(a[k] - b[k])) for k in a)) * 1e3


def main(argv) -> int:
    from pixelkit.chip.frame import CONVERGED
    a, d, ph = chip_slice(argv, 2, "gradient", (("--only", ""),))
    sets = {"kit": (), **{k: v for k, v in CANDIDATES.items() if not a.only or k in a.only.split(",")},
            "converged": CONVERGED}
    runs = {}
    for name, opts in sets.items():
        f, cpu, wall = _frame(d, ph, opts)
        runs[name] = {"cpu_s": round(cpu, 2), "wall_s": round(wall, 1), "decks": f.decks, "load": round(os.getloadavg()[0], 1),
                      "retried": len(f.retried), "failures": len(f.failures), "fig": _figures(f)}
        if not a.json:
            print(f"  {name}: {cpu:.1f} s CPU, {f.decks} decks", file=sys.stderr)
    base, conv = runs["kit"], runs["converged"]
    base_err = _diff_mV(base["fig"], conv["fig"])
    out = {"design": Path(a.design).name, "rows": a.rows, "cols": a.cols, "keep_mV": KEEP_MV, "sets": {}}
    for name, r in runs.items():
        vs_kit = _diff_mV(r["fig"], base["fig"])
        vs_conv = _diff_mV(r["fig"], conv["fig"])
        out["sets"][name] = {**{k: v for k, v in r.items() if k != "fig"}, "cpu_ratio": round(r["cpu_s"] / base["cpu_s"], 3),
                             "vs_kit_mV": round(vs_kit, 4), "vs_converged_mV": round(vs_conv, 4),
                             "keeps": name == "kit" or (vs_kit <= KEEP_MV and vs_conv <= base_err * 1.001)}
    if a.json:
        print(json.dumps(out, indent=1))
        return 0
    print(f"{out['design']}, {a.rows} x {a.cols} with the AFE and the settling reads (load {runs['kit']['load']}):")
    for name, r in out["sets"].items():
        print(f"  {name:14s} {r['cpu_s']:7.1f} s CPU ({r['cpu_ratio']:.3f} of kit), {r['decks']} decks, "
              f"vs kit {r['vs_kit_mV']:.4f} mV, vs converged {r['vs_converged_mV']:.4f} mV"
              f"{'' if name in ('kit', 'converged') else ('  keeps' if r['keeps'] else '  MOVES')}"
              f"{', retried ' + str(r['retried']) if r['retried'] else ''}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
