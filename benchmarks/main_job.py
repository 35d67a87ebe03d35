"""The main job, part by part, against an earlier commit's code and against raw ngspice, in one run.

    python3 benchmarks/main_job.py [--baseline REV] [--parts report,verify,gap,afe4x4,chip]
                                   [--no-baseline | --baseline-parts P,..] [--no-raw] [--json] [--keep DIR]

Each part is a command as a user types it, on the reference design, run in a fresh process with an
EMPTY simulation cache of its own:

- ``report``: ``pixelkit report designs/dual_pixel_revA.toml`` (the README's first command: the full
  profile, the sign-off grid and its Monte Carlo included);
- ``verify``: ``pixelkit verify designs/dual_pixel_revA.toml`` (45 conditions, Monte Carlo 200);
- ``gap``: ``pixelkit gap predict designs/dual_pixel_revA.toml --conditions examples/measured_revA.csv``
  (the reference design ships no surrogate: its first prediction builds one from SPICE);
- ``afe4x4``: ``pixelkit array ... --rows 4 --cols 4 --afe --check``;
- ``chip``: ``pixelkit array ... --rows 27 --cols 50 --afe`` (the whole chip with every column's AFE).

For each: wall time, CPU time (the command and every process it waited for: ngspice, KLayout),
the largest process's resident memory, the SPICE runs and simulated (transient) time per figure
group (from the decks the command handed to ngspice, recorded by ``benchmarks/deck_log.py``), and
two ratios measured in this same run:

- ``vs baseline``: the same command, same inputs (this tree's design and data files), with the
  code of ``--baseline`` (default ``BASELINE``: main before issue 41's levers) checked out in a
  temporary git worktree: the parts alternate which code runs first, so load drifting during the
  run hits both sides;
- ``vs raw``: every deck the command simulated, replayed with plain ``ngspice -b`` on as many
  parallel workers as the kit uses: the kit's cost beyond the simulations themselves (its Python,
  its cache, its serial stretches). A command that simulates fewer decks than before gains
  against the baseline, not against raw.

The machine's 1-minute load average is printed before and after every command: on a shared
machine the wall times move with it (the CPU times much less); docs/benchmarks.md quotes runs
with their load.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HOOK = Path(__file__).resolve().parent / "deck_log.py"
#: main before issue 41's levers (684a51f brought the sequential Monte Carlo).
BASELINE = "2b2e64c"
DESIGN = ROOT / "designs" / "dual_pixel_revA.toml"
PARTS = {
    "report": ["report", str(DESIGN), "--out", "{out}/report"],
    "verify": ["verify", str(DESIGN), "--out", "{out}/verify", "--json"],
    "gap": ["gap", "predict", str(DESIGN), "--conditions", str(ROOT / "examples" / "measured_revA.csv"),
            "--out", "{out}/predicted.csv", "--json"],
    "afe4x4": ["array", str(DESIGN), "--rows", "4", "--cols", "4", "--afe", "--check", "--json"],
    "chip": ["array", str(DESIGN), "--rows", "27", "--cols", "50", "--afe", "--json"],
}
#: Figure group of a deck, by its title (verify.measure's groups; other sections' decks by what they are).
GROUPS = [(r"^vfy_(dark|small|sat|mid_lo|mid_hi)$", "pixel"), (r"^vfy_lag_", "lag"), (r"^vfy_gse_", "gse"),
          (r"^vfy_sf_", "noise"), (r"^vfy_dark_[ps]$", "dark"), (r"^vfy_afe", "afe"), (r"^vfy_power_", "power"),
          (r"^frame_2x1_", "settling"), (r"^frame_", "frames"), (r"^gap", "gap surrogate"),
          (r"^(coarse|refine)\d", "experiment (fig. A.1 - A.3)")]


def group_of(title: str) -> str:
    for pattern, name in GROUPS:
        if re.search(pattern, title):
            return name
    return "other: " + re.sub(r"[0-9_]+$", "", title)[:24]


def run_part(tree: Path, argv: list, folder: Path) -> dict:
    """One command with ``tree``'s code in a fresh process and an empty cache; its decks logged."""
    folder.mkdir(parents=True)
    env = dict(os.environ, PYTHONPATH=str(tree), PIXELKIT_CACHE=str(folder / "cache"), PIXELKIT_PROGRESS="0")
    args = [a.replace("{out}", str(folder / "out")) for a in argv]
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    with open(folder / "stdout", "w") as out, open(folder / "stderr", "w") as err:
        p = subprocess.Popen([sys.executable, str(HOOK), str(folder / "log"), *args], cwd=tree, env=env,
                             stdout=out, stderr=err, stdin=subprocess.DEVNULL)
        _, status, ru = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    decks = [json.loads(x) for x in (folder / "log" / "decks.jsonl").read_text().splitlines()] \
        if (folder / "log" / "decks.jsonl").exists() else []
    groups: dict = defaultdict(lambda: {"runs": 0, "simulated_s": 0.0, "deck_wall_s": 0.0})
    for d in decks:
        g = groups[group_of(d["title"])]
        g["runs"] += 1
        g["simulated_s"] += d["tran_stop_s"] or 0.0
        g["deck_wall_s"] += d["wall_s"]
    return {"wall_s": wall, "cpu_s": ru.ru_utime + ru.ru_stime, "max_rss_MB": ru.ru_maxrss / 1024,
            "exit": os.waitstatus_to_exitcode(status), "spice_runs": len(decks), "groups": dict(groups),
            "load_before": load0, "load_after": os.getloadavg()[0], "log": str(folder / "log"),
            "stderr_tail": (folder / "stderr").read_text()[-600:]}


def _replay_one(log: Path, deck: dict, spiceinit: str) -> float:
    with tempfile.TemporaryDirectory(prefix="pk-raw-") as tmp:
        Path(tmp, ".spiceinit").write_text(spiceinit)
        for name, target in deck["links"].items():
            Path(tmp, name).symlink_to(target)
        shutil.copy(log / deck["file"], Path(tmp, "deck.cir"))
        t0 = time.perf_counter()
        subprocess.run(["ngspice", "-b", "-r", "out.raw", "deck.cir"], cwd=tmp, capture_output=True,
                       stdin=subprocess.DEVNULL)
        return time.perf_counter() - t0


def replay(log: Path, jobs: int) -> dict:
    """Every deck of a logged command with plain ``ngspice -b``, ``jobs`` at a time (the kit's
    ``.spiceinit``: one thread per ngspice, as the kit runs it)."""
    decks = [json.loads(x) for x in (log / "decks.jsonl").read_text().splitlines()]
    spiceinit = "set num_threads=1\n"
    c0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    with ThreadPoolExecutor(max_workers=jobs) as ex:
        walls = list(ex.map(lambda d: _replay_one(log, d, spiceinit), decks))
    c1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return {"wall_s": time.perf_counter() - t0, "decks": len(decks), "deck_wall_s": sum(walls),
            "cpu_s": (c1.ru_utime + c1.ru_stime) - (c0.ru_utime + c0.ru_stime), "jobs": jobs}


def checkout(rev: str, where: Path) -> Path:
    subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(where), rev], check=True,
                   capture_output=True)
    return where


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", default=BASELINE, help=f"the earlier commit to compare with (default {BASELINE})")
    ap.add_argument("--parts", default=",".join(PARTS), help="comma-separated, of: " + ", ".join(PARTS))
    ap.add_argument("--no-baseline", action="store_true", help="measure this tree only")
    ap.add_argument("--baseline-parts", default=None,
                    help="run the baseline only for these parts (comma-separated; default: every part)")
    ap.add_argument("--no-raw", action="store_true", help="skip the raw ngspice replay")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--keep", default=None, help="keep the runs' folders (logs, decks, outputs) here")
    a = ap.parse_args(argv)
    parts = [p.strip() for p in a.parts.split(",") if p.strip()]
    for p in parts:
        if p not in PARTS:
            raise SystemExit(f"main_job: unknown part {p!r}; allowed: {', '.join(PARTS)}")
    sys.path.insert(0, str(ROOT))
    from pixelkit.spice.engine import default_jobs
    jobs = default_jobs()
    work = Path(a.keep).resolve() if a.keep else Path(tempfile.mkdtemp(prefix="pk-mainjob-"))
    work.mkdir(parents=True, exist_ok=True)
    head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                          text=True).stdout.strip()
    res = {"head": head, "baseline": None if a.no_baseline else a.baseline, "cores": os.cpu_count(), "jobs": jobs,
           "parts": {}}
    base_tree = None
    try:
        if not a.no_baseline:
            base_tree = checkout(a.baseline, work / "baseline-tree")
        for k, name in enumerate(parts):
            with_base = base_tree is not None and (a.baseline_parts is None or name in a.baseline_parts.split(","))
            sides = [("current", ROOT)] + ([("baseline", base_tree)] if with_base else [])
            if k % 2:
                sides.reverse()
            out = {}
            for side, tree in sides:
                print(f"main_job: {name} with the {side} code ...", file=sys.stderr, flush=True)
                out[side] = run_part(tree, PARTS[name], work / name / side)
            if not a.no_raw:
                print(f"main_job: {name}: raw ngspice replay ...", file=sys.stderr, flush=True)
                out["raw"] = replay(Path(out["current"]["log"]), jobs)
            res["parts"][name] = out
            (work / "results.json").write_text(json.dumps(res, indent=1))   # a long run's parts so far
    finally:
        if base_tree is not None:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(base_tree)],
                           capture_output=True)
        if not a.keep:
            shutil.rmtree(work, ignore_errors=True)
    if a.json:
        print(json.dumps(res, indent=1))
    else:
        print(text(res))


def _run_text(r: dict) -> str:
    """One command's or replay's figures."""
    extra = (f", largest process {r['max_rss_MB']:.0f} MB, {r['spice_runs']} SPICE runs, exit {r['exit']}, load "
             f"{r['load_before']:.1f} -> {r['load_after']:.1f}" if "exit" in r else f", {r['decks']} decks on "
             f"{r['jobs']} workers")
    return f"wall {r['wall_s']:.1f} s, CPU {r['cpu_s']:.1f} s" + extra


def text(res: dict) -> str:
    lines = [f"main job at {res['head']} against {res['baseline'] or '(no baseline)'}, {res['cores']} cores, "
             f"{res['jobs']} workers"]
    for name, out in res["parts"].items():
        cur = out["current"]
        lines.append(f"\n{name}: {_run_text(cur)}")
        for side, label in (("baseline", "baseline"), ("raw", "raw ngspice on the same decks")):
            if side in out:
                o = out[side]
                lines.append(f"  {label}: {_run_text(o)}; current / {side}: wall {cur['wall_s'] / o['wall_s']:.3f}, "
                             f"CPU {cur['cpu_s'] / max(o['cpu_s'], 1e-9):.3f}")
        names = sorted(set(cur["groups"]) | set(out.get("baseline", {}).get("groups", {})))
        for g in names:
            c = cur["groups"].get(g, {"runs": 0, "simulated_s": 0.0, "deck_wall_s": 0.0})
            row = (f"  {g:26s} {c['runs']:6d} runs, {c['simulated_s'] * 1e3:9.3f} ms simulated, "
                   f"{c['deck_wall_s']:8.1f} s of deck wall")
            if "baseline" in out:
                bg = out["baseline"]["groups"].get(g, {"runs": 0, "simulated_s": 0.0})
                row += f"   (baseline {bg['runs']} runs, {bg['simulated_s'] * 1e3:.3f} ms)"
            lines.append(row)
    return "\n".join(lines)


if __name__ == "__main__":
    main(sys.argv[1:])
