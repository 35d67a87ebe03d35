"""Extraction CPU: the 2.5D model with its far field (``capacitance.capacitances``) on the flat 2 x 2 chip
with its AFEs (what ``pixelkit signoff`` extracts) and on the cells the post-layout view extracts, this
checkout against another revision of the kit measured in the same run.

Each side runs in a fresh process (the other revision exported by ``git archive`` into a temporary
folder): it draws the 2 x 2 chip of ``designs/dual_pixel_gf180.toml`` with its AFEs, reads each cell's
geometry as ``signoff`` does (LVS net names), then times ``capacitances`` on each (CPU: user + system of
the process; wall), the far field (``farfield.far_couplings``) apart. Printed: both sides' times, the
ratio this / baseline (CPU and wall; the CPU ratio is the one the machine's load moves least), and the
largest relative difference of any coupling above 1 aF between the two (a speed change that is meant not
to move the numbers must show ~0).

    python3 benchmarks/extraction_speed.py [--against REV]      # REV: default main
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import ROOT

CELLS = ("DUALPIX", "DUALPIX_COL", "AFE_P", "AFE_S")


def measure() -> dict:
    """This process's kit (its ``sys.path[0]``): {cell: {cpu, wall, far_cpu, couplings}} (chip: ``chip``)."""
    import resource
    from pixelkit.design import load_design
    from pixelkit.layout.flow import layout_design
    from pixelkit.layout.pex import capacitance, farfield
    from pixelkit.layout.pex.nets import view_geometry
    from pixelkit.layout.signoff.gds_in import read_layout
    from pixelkit.layout.signoff.netlist_in import read_netlist

    def cpu():
        r = resource.getrusage(resource.RUSAGE_SELF)
        return r.ru_utime + r.ru_stime
    spent = {"far": 0.0}
    inner = farfield.far_couplings

    def timed_far(*a):
        c0 = cpu()
        try:
            return inner(*a)
        finally:
            spent["far"] += cpu() - c0
    capacitance.far_couplings = timed_far
    d = load_design(ROOT / "designs" / "dual_pixel_gf180.toml")
    work = Path(tempfile.mkdtemp(prefix="pk-extspeed-"))
    r = layout_design(d, work / "drawn", 2, 2, pictures=False, afe=True)
    gds, spice = Path(r["gds"]), {k: Path(v) for k, v in r["spice"].items()}
    out = {}
    for cell in (*CELLS, r["top"]):
        (work / f"r_{cell}").mkdir()
        lay = read_layout(gds, d.tech, cell, work / f"r_{cell}")
        geo = view_geometry(lay.path, cell, d.tech, read_netlist(spice[cell], d.tech).top_view(cell))
        spent["far"] = 0.0
        c0, t0 = cpu(), time.perf_counter()
        cpl = capacitance.capacitances(geo, d.tech.stack)
        out["chip" if cell == r["top"] else cell] = {
            "cpu": cpu() - c0, "wall": time.perf_counter() - t0, "far_cpu": spent["far"],
            "couplings": {f"{a}|{b}": v for (a, b), v in cpl.items() if v > 1e-18}}
    return out


def run_side(src: Path) -> dict:
    """``measure`` in a fresh process importing the kit at ``src``."""
    code = (f"import sys, json; sys.path.insert(0, {str(src)!r}); import pixelkit; sys.path.insert(1, {str(ROOT / 'benchmarks')!r}); "
            "import extraction_speed as e; print('RESULT' + json.dumps(e.measure()))")
    env = dict(os.environ, PYTHONPATH=str(src), PIXELKIT_CACHE=tempfile.mkdtemp(prefix="pk-extspeed-cache-"))
    p = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, cwd=src)
    line = [x for x in p.stdout.splitlines() if x.startswith("RESULT")]
    if p.returncode or not line:
        sys.exit(f"the run of {src} failed:\n{p.stderr[-3000:]}")
    return json.loads(line[-1][len("RESULT"):])


def main(rev: str) -> None:
    base_dir = Path(tempfile.mkdtemp(prefix="pk-extspeed-base-"))
    arch = subprocess.run(["git", "-C", str(ROOT), "archive", rev], capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(base_dir)], input=arch, check=True)
    sha = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", rev], capture_output=True, text=True).stdout.strip()
    load0 = os.getloadavg()[0]
    base = run_side(base_dir)
    this = run_side(ROOT)
    print(f"extraction CPU, this checkout against {rev} ({sha}), load average {load0:.2f} -> {os.getloadavg()[0]:.2f} "
          f"on {os.cpu_count()} cores")
    print(f"  {'cell':12s} {'baseline CPU':>12s} {'(far)':>8s} {'this CPU':>9s} {'(far)':>8s} {'CPU ratio':>9s} "
          f"{'wall ratio':>10s} {'max diff':>9s}")
    for cell in (*CELLS, "chip"):
        b, t = base[cell], this[cell]
        keys = set(b["couplings"]) | set(t["couplings"])
        diff = max((abs(t["couplings"].get(k, 0.0) - b["couplings"].get(k, 0.0))
                    / max(b["couplings"].get(k, 0.0), t["couplings"].get(k, 0.0)) for k in keys), default=0.0)
        print(f"  {cell:12s} {b['cpu']:10.2f} s {b['far_cpu']:6.2f} s {t['cpu']:7.2f} s {t['far_cpu']:6.2f} s "
              f"{t['cpu'] / b['cpu']:9.2f} {t['wall'] / b['wall']:10.2f} {diff * 100:8.3f} %")


if __name__ == "__main__":
    args = sys.argv[1:]
    main(args[args.index("--against") + 1] if "--against" in args else "main")
