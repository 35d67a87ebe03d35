"""The report's layout sign-off with and without the DRC cache, in one run.

    python3 benchmarks/signoff_cache.py [designs/dual_pixel_revB.toml] [--json]

What the report's ``layout_signoff`` section does (``layout_design``: the 2 x 2 array with its AFE
columns and the full shield, the foundry's DRC deck, the kit's LVS), twice, on one fresh private
cache: first the deck runs (the baseline: an empty DRC cache, what every report paid before the
cache), then the same drawing again (the deck's result from the DRC cache). Printed for each: wall
and CPU seconds (this process and every child it waited for: KLayout), the DRC and LVS seconds
the results state, and the ratio second / first; the two results are compared (violations, the
deck's report byte for byte): a cache that changed the verdict would be said and exit 1.
"""
from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path

from common import ROOT, child_cpu_s


def _cpu() -> float:
    t = os.times()
    return t.user + t.system + child_cpu_s()


def main(design_file: Path, as_json: bool) -> int:
    os.environ["PIXELKIT_CACHE"] = tempfile.mkdtemp(prefix="pk-bench-signoff-")
    from pixelkit.design import load_design
    from pixelkit.layout.flow import layout_design
    d = load_design(design_file)
    work = Path(tempfile.mkdtemp(prefix="pk-bench-signoff-out-"))
    runs = []
    for name in ("deck run", "cached"):
        load0 = os.getloadavg()[0]
        c0, t0 = _cpu(), time.perf_counter()
        r = layout_design(d, work / name.replace(" ", "_"), 2, 2, pictures=False, drc=True, lvs=True, afe=True,
                          shield="full", drc_cache=True)
        runs.append({"name": name, "wall_s": round(time.perf_counter() - t0, 2), "cpu_s": round(_cpu() - c0, 2),
                     "drc_s": r["drc"]["seconds"], "drc_cached": r["drc"].get("cached", False),
                     "lvs_s": r["lvs"]["seconds"], "load": [round(load0, 1), round(os.getloadavg()[0], 1)],
                     "violations": r["drc"]["violations"], "report": Path(r["drc"]["report"]).read_bytes()})
    a, b = runs
    same = a["violations"] == b["violations"] and a["report"] == b["report"]
    out = {"design": design_file.name, "same_result": same, "cpu_ratio": round(b["cpu_s"] / a["cpu_s"], 3),
           "wall_ratio": round(b["wall_s"] / a["wall_s"], 3),
           "runs": [{k: v for k, v in r.items() if k not in ("violations", "report")} for r in runs]}
    if as_json:
        print(json.dumps(out, indent=1))
    else:
        for r in out["runs"]:
            print(f"{r['name']:8s}: {r['wall_s']:7.2f} s wall, {r['cpu_s']:7.2f} s CPU (DRC {r['drc_s']} s"
                  f"{', from the cache' if r['drc_cached'] else ''}; LVS {r['lvs_s']} s), load {r['load']}")
        print(f"cached / deck run: CPU {out['cpu_ratio']}, wall {out['wall_ratio']}; the same violations and "
              f"report bytes: {'yes' if same else 'NO'}")
    return 0 if same and b["drc_cached"] else 1


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    sys.exit(main(Path(args[0]) if args else ROOT / "designs" / "dual_pixel_revB.toml", "--json" in sys.argv))
