"""The cost of ``pixelkit close``: SPICE runs and wall time per iteration and in total, and how they
grow with the number of knobs (2, 5, 10), against one plain ``verify`` of the same design and grid
measured in the same run (the unit a designer knows: "close costs N sign-offs").

    python3 benchmarks/close.py [--knobs 2,5,10] [--grid small|full] [--mc N] [--max-iterations N]
                                [--design FILE] [--reference] [--base REV] [--json]

For each knob count, with a fresh empty simulation cache each (``PIXELKIT_CACHE``): ``pixelkit verify``
of the design with that grid (the baseline), then ``pixelkit close`` of the same design with the
benchmark's ``[close]`` table (objective min power; the knobs below, the first N), each in its own
process as a user runs them. Printed: per iteration (from close.json) the mode, whether it was
accepted, where it was verified, SPICE runs, cache hits and wall time; the totals; the ratios close /
verify in runs, wall and CPU (the command and its ngspice children; on a machine others load, CPU is
the figure load moves least); and the growth of the runs per iteration from 2 knobs to 5 and 10.

``--grid small``: corners tt and ss x 27 and 85 degC x -10 % and 0 % (8 conditions), the growth
study; ``--grid full``: the design's own ``[verify]`` grid (the reference: 45 conditions) with its
Monte Carlo unless ``--mc``. ``--reference``: the design's own grid, Monte Carlo and ``[close]`` table (the reference's: the
gates' drive as a circuit choice, the rail, both resets, the transistor OTA's bias and compensation,
the AFE's capacitors): "close on the reference from an empty cache" (issue 40: within 30 min on 2
cores), the run that writes designs/dual_pixel_revB.toml.

``--base REV``: a change to close itself, measured against the kit at git revision ``REV`` (say
``HEAD~1``) in the same run: both closes run side by side, each from its own empty cache, the base with
``REV``'s code (``git archive`` into a temporary folder), and the ratios new / base are printed (CPU,
SPICE runs, wall) with both results (status, candidates, objective): a cut that moves the result shows
here. No verify baseline is run then.
"""
from __future__ import annotations

import argparse
import atexit
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

from common import ROOT, child_cpu_s

#: The knobs, in the order they are added (each moves at least one spec of the reference).
KNOBS = [
    ("pixel.v_pd_reset", ["1.6 V", "2.2 V"]),
    ("pixel.sf_bias", {"min": "600 nA", "max": "1.5 uA", "scale": "log"}),
    ("pixel.v_fd_reset", ["1.6 V", "2.2 V"]),
    ("afe.c13", ["250 fF", "1 pF"]),
    ("pixel.devices.sf_w", {"min": "0.5 um", "max": "3 um", "step": "5 nm"}),
    ("pixel.devices.tg_w", {"min": "0.42 um", "max": "1.2 um", "step": "5 nm"}),
    ("pixel.devices.ec_w", {"min": "0.42 um", "max": "1.2 um", "step": "5 nm"}),
    ("pixel.devices.rst_w", {"min": "0.42 um", "max": "1.2 um", "step": "5 nm"}),
    ("afe.gbw", ["20 MHz", "100 MHz"]),
    ("secondary.t_int", ["8 ms", "16 ms"]),
]
SMALL = {"corners": ["tt", "ss"], "temperatures": ["27 degC", "85 degC"], "supplies": ["-10 %", "0 %"]}
def design_file(src: Path, n: int, grid: str, mc: int | None, max_iterations: int, folder: Path) -> Path:
    """The design's file with the benchmark's [close] table (the first ``n`` knobs) and grid."""
    from pixelkit.schema import to_toml
    if n == 0 and grid == "full" and mc is None:   # --reference: the design file itself, as a user runs it
        return src
    text = src.read_text()
    raw = tomllib.loads(text)
    verify = dict(raw.get("verify", {}))
    if grid == "small":
        verify.update(SMALL)
    if mc is not None:
        verify["mc"] = mc
    close = (raw["close"] if n == 0 else     # --reference: the design's own [close] table
             {"objective": "min power", "max_iterations": max_iterations, "knobs": dict(KNOBS[:n])})
    head = text.split("\n[verify]")[0] if "\n[verify]" in text else text.split("\n[spec.")[0]
    body = {k: v for k, v in raw.items() if k in ("spec",)}
    path = folder / f"bench_{n}.toml"
    if raw["technology"].endswith(".toml"):
        head = head.replace(f'"{raw["technology"]}"', f'"{(src.parent / raw["technology"]).resolve()}"')
    path.write_text(head + "\n" + to_toml({"verify": verify, **body, "close": close}))
    return path


def timed(cmd: list, env: dict) -> tuple[subprocess.CompletedProcess, float, float]:
    t0, c0 = time.perf_counter(), child_cpu_s()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT)
    return p, time.perf_counter() - t0, child_cpu_s() - c0


def scratch_cache(prefix: str) -> str:
    """An empty simulation cache for one run, removed when the benchmark ends (a close's cache is GBs)."""
    path = tempfile.mkdtemp(prefix=prefix)
    atexit.register(shutil.rmtree, path, ignore_errors=True)
    return path


def base_tree(rev: str) -> Path:
    """The kit at git revision ``rev``, unpacked into a temporary folder (exit 2 when ``rev`` is no commit)."""
    found = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--verify", "--quiet", "--end-of-options",
                            f"{rev}^{{commit}}"], capture_output=True, text=True)
    if found.returncode != 0 or rev.startswith("-"):
        print(f"error: --base {rev!r}: not a commit of this repository (a hash, tag or branch)", file=sys.stderr)
        raise SystemExit(2)
    rev = found.stdout.strip()
    out = Path(tempfile.mkdtemp(prefix="pk-bench-base-"))
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev], capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(out)], input=archive, check=True)
    return out


def closes(d: Path, n: int, folder: Path, base: Path | None) -> list[tuple[dict, float, float, int]]:
    """``pixelkit close`` of ``d`` with this kit (and, with ``base``, the base kit's, side by side), each from
    its own empty cache: [(close.json, wall, CPU, exit)] (CPU: close's own count, the command and its ngspice
    runs, as two processes run at once)."""
    runs = []
    for tag, root in [("", ROOT)] + ([("base_", base)] if base else []):
        env = dict(os.environ, PIXELKIT_CACHE=scratch_cache("pk-bench-close-"), PIXELKIT_PROGRESS="0",
                   PYTHONPATH=str(root))
        out = folder / f"{tag}closed_{n}.toml"
        design = root / d.relative_to(ROOT) if d.is_relative_to(ROOT) else d   # a kit's own design file
        p = subprocess.Popen([sys.executable, "-m", "pixelkit", "close", str(design), "--out", str(out), "--json"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=root)
        runs.append((p, time.perf_counter()))
    done = []
    for p, t0 in runs:
        stdout, stderr = p.communicate()
        done.append((p, stdout, stderr, time.perf_counter() - t0))
    out = []
    for p, stdout, stderr, wall in done:
        if p.returncode not in (0, 1, 5):
            raise SystemExit(f"close exited {p.returncode}: {stderr[-2000:]}")
        r = json.loads(stdout)
        out.append((r, wall, r.get("cpu_s"), p.returncode))
    return out


def summary(r: dict, wall: float, cpu: float, code: int) -> dict:
    """What the benchmark keeps of a close.json (``r``), its wall and CPU time and its exit status."""
    return {"wall_s": wall, "cpu_s": cpu, "spice_runs": r["spice_runs"], "cached": r["spice_cached"],
            "status": r["status"], "exit": code, "candidates": len(r["iterations"]) - 1,
            "objective": r["objective"], "smallest_margin_pct": r["smallest_margin_pct"],
            "conflict": (r.get("conflict") or {}).get("text"), "overrides": r.get("overrides"),
            "cpu_s_own": r.get("cpu_s"), "choices": r.get("choices"), "yield": r.get("yield"),
            "iterations": [{k: i.get(k) for k in ("iteration", "mode", "accepted", "verified_on", "spice_runs",
                                                  "spice_cached", "cpu_s", "wall_s", "smallest_margin_pct", "choice")}
                           for i in r["iterations"]]}


def against(src: Path, n: int, args, folder: Path) -> dict:
    """This kit's close and the base revision's, side by side in the same run."""
    d = design_file(src, n, args.grid, args.mc, args.max_iterations, folder)
    tree = base_tree(args.base)
    try:
        (new, base) = closes(d, n, folder, tree)
    finally:
        shutil.rmtree(tree, ignore_errors=True)
    return {"knobs": n, "base": args.base, "close": summary(*new), "base_close": summary(*base)}


def one(src: Path, n: int, args, folder: Path) -> dict:
    d = design_file(src, n, args.grid, args.mc, args.max_iterations, folder)
    env = dict(os.environ, PIXELKIT_CACHE=scratch_cache("pk-bench-verify-"), PIXELKIT_PROGRESS="0")
    p, v_wall, v_cpu = timed([sys.executable, "-m", "pixelkit", "verify", str(d), "--mc", "0", "--json",
                              "--out", str(folder / f"verify_{n}")], env)
    if p.returncode not in (0, 1, 4, 5):
        raise SystemExit(f"verify exited {p.returncode}: {p.stderr[-2000:]}")
    v = json.loads(p.stdout)
    v_runs = sum(1 for _ in Path(env["PIXELKIT_CACHE"], "sim").rglob("*.entry"))
    env = dict(os.environ, PIXELKIT_CACHE=scratch_cache("pk-bench-close-"), PIXELKIT_PROGRESS="0")
    out = folder / f"closed_{n}.toml"
    p, c_wall, c_cpu = timed([sys.executable, "-m", "pixelkit", "close", str(d), "--out", str(out), "--json"], env)
    if p.returncode not in (0, 1, 5):
        raise SystemExit(f"close exited {p.returncode}: {p.stderr[-2000:]}")
    r = json.loads(p.stdout)
    return {"knobs": n, "conditions": v["grid"]["conditions"], "verify": {"wall_s": v_wall, "cpu_s": v_cpu,
                                                                          "spice_runs": v_runs},
            "close": summary(r, c_wall, c_cpu, p.returncode)}


def stages(c: dict) -> list[tuple[str, int, float]]:
    """Where the CPU went: (stage, SPICE runs, CPU s) from close.json's records (each record holds the work
    since the one before: a candidate's sensitivities count with it)."""
    out: dict = {}

    def add(name, runs, cpu):
        r0, c0 = out.get(name, (0, 0.0))
        out[name] = (r0 + (runs or 0), c0 + (cpu or 0.0))
    for ch in c.get("choices") or []:
        sc = ch.get("screen") or {}
        if sc.get("cpu_s") is not None:
            add("choice screen (the first choice's start grid + the others at its worst conditions)",
                sc.get("spice_runs"), sc.get("cpu_s"))
    for i in c["iterations"]:
        name = {"start": "start (whole grid; replayed after a choice screen)",
                "global": "global stage (samples, then its choice on the grid)"}.get(
            i["mode"], ("grid-verified candidates and checks" if i["verified_on"] == "grid" else
                        "screened candidates (with their sensitivities)"))
        add(name, i["spice_runs"], i.get("cpu_s"))
    y = c.get("yield") or {}
    if y.get("cpu_s") is not None:
        add(f"Monte Carlo yield ({y.get('samples')} samples)", y.get("spice_runs"), y.get("cpu_s"))
    return [(k, r, cpu) for k, (r, cpu) in out.items()]


def show(res: dict) -> None:
    c, v = res["close"], res["verify"]
    print(f"\n{res['knobs'] or 'the reference'} knobs, {res['conditions']} conditions: close {c['status']} (exit {c['exit']}) after "
          f"{c['candidates']} candidates, smallest margin {c['smallest_margin_pct'] if c['smallest_margin_pct'] is None else round(c['smallest_margin_pct'], 3)} %, objective "
          f"{c['objective']['shown_start']} -> {c['objective']['shown']}"
          + (f"; conflict: {c['conflict']}" if c["conflict"] else ""))
    for ch in c.get("choices") or []:
        sc = ch.get("screen") or {}
        print(f"  choice {ch['choice']}: {ch['status']}" + (f", screen: {0.0 - sc['behind_pct']:.3g} % behind the best "
                                                         f"({sc.get('worst')})" if sc.get("behind_pct") is not None
                                                         else ""))
    print("  iteration  mode      accepted  verified on          SPICE runs  cached  CPU (s)  wall at end (s)")
    for i in c["iterations"]:
        cpu = "-" if i.get("cpu_s") is None else f"{i['cpu_s']:.0f}"
        print(f"  {i['iteration']:>9}  {i['mode']:<8}  {'yes' if i['accepted'] else 'no':<8}  {i['verified_on']:<19}  "
              f"{i['spice_runs']:>10}  {i['spice_cached']:>6}  {cpu:>7}  {i['wall_s']:>15.0f}")
    print("  where the CPU went (close's own count: the command and its ngspice runs):")
    for name, runs, cpu in stages(c):
        print(f"    {name:<88} {runs:>6} runs {cpu:>7.0f} s CPU")
    print(f"  close:  {c['spice_runs']} SPICE runs, {c['wall_s']:.0f} s wall, {c['cpu_s']:.0f} s CPU (the command and "
          "its ngspice runs)")
    print(f"  verify: {v['spice_runs']} SPICE runs, {v['wall_s']:.0f} s wall, {v['cpu_s']:.0f} s CPU (ngspice), "
          "the same grid, no Monte Carlo")
    print(f"  ratio close / verify: runs {c['spice_runs'] / max(v['spice_runs'], 1):.1f}, wall "
          f"{c['wall_s'] / v['wall_s']:.1f}, CPU {c['cpu_s'] / max(v['cpu_s'], 1e-9):.1f}")


def show_against(res: dict) -> None:
    c, b = res["close"], res["base_close"]
    print(f"\n{res['knobs'] or 'the reference'} knobs: this kit against {res['base']}, side by side, each from an "
          "empty cache")
    for tag, r in (("this kit", c), (res["base"], b)):
        print(f"  {tag:<10} {r['status']} (exit {r['exit']}) after {r['candidates']} candidates, "
              f"{r['objective']['shown_start']} -> {r['objective']['shown']}; {r['spice_runs']} SPICE runs, "
              f"{r['cpu_s']:.0f} s CPU, {r['wall_s']:.0f} s wall")
        print("    " + ", ".join(f"{k} {v}" for k, v in sorted((r.get("overrides") or {}).items())))
        for name, runs, cpu in stages(r):
            print(f"    {name:<88} {runs:>6} runs {cpu:>7.0f} s CPU")
    same = c["overrides"] == b["overrides"] and c["status"] == b["status"]
    print(f"  the same revision: {'yes' if same else 'NO'}; ratio this kit / {res['base']}: CPU "
          f"{c['cpu_s'] / b['cpu_s']:.3f}, SPICE runs {c['spice_runs'] / max(b['spice_runs'], 1):.3f}, wall "
          f"{c['wall_s'] / b['wall_s']:.3f} (wall: both ran at once)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--knobs", default="2,5,10")
    ap.add_argument("--grid", choices=("small", "full"), default="small")
    ap.add_argument("--mc", type=int, default=None, help="Monte Carlo samples (default: 0 on the small grid, the "
                                                         "design's on the full one)")
    ap.add_argument("--max-iterations", type=int, default=15)
    ap.add_argument("--design", type=Path, default=ROOT / "designs" / "dual_pixel_revA.toml")
    ap.add_argument("--reference", action="store_true",
                    help="the reference run instead: the design's full grid, Monte Carlo and [close] table")
    ap.add_argument("--base", default=None, help="a git revision: this kit's close against that revision's, "
                                                  "side by side in the same run (no verify baseline)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    if args.reference:
        args.grid, args.knobs = "full", "0"
    if args.mc is None and args.grid == "small":
        args.mc = 0
    counts = [int(x) for x in args.knobs.split(",")]
    folder = Path(tempfile.mkdtemp(prefix="pk-bench-close-"))
    load = os.getloadavg()[0]
    results = [(against if args.base else one)(args.design, n, args, folder) for n in counts]
    if args.json:
        print(json.dumps({"results": results, "load_at_start": load, "load_at_end": os.getloadavg()[0]}, indent=1))
        return
    print(f"pixelkit close on {args.design.name}, grid {args.grid}, load average {load:.1f} at the start, "
          f"{os.getloadavg()[0]:.1f} at the end; files in {folder}")
    for res in results:
        (show_against if args.base else show)(res)
    if args.base:
        return
    base = results[0]
    per = {r["knobs"]: r["close"]["spice_runs"] / max(r["close"]["candidates"], 1) for r in results}
    if len(results) > 1:
        print("\ngrowth with the knobs (SPICE runs per candidate, total runs, wall), against "
              f"{base['knobs']} knobs:")
        for r in results:
            print(f"  {r['knobs']:>2} knobs: {per[r['knobs']]:.0f} runs per candidate "
                  f"(x{per[r['knobs']] / per[base['knobs']]:.2f}), total runs x"
                  f"{r['close']['spice_runs'] / base['close']['spice_runs']:.2f}, wall x"
                  f"{r['close']['wall_s'] / base['close']['wall_s']:.2f}")


if __name__ == "__main__":
    main()
