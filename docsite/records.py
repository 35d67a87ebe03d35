"""Dated measurement records: a run no test repeats (a full-grid sign-off, a post-layout grid), stored
with what it printed and when, on what, so a page can quote it and a test can hold the page to it.

    python -m docsite.records run NAME -- pixelkit verify designs/dual_pixel_revB.toml

runs the command from the repository's root (``pixelkit`` and ``python`` are this interpreter) and
writes ``docs/records/NAME.json``: the command, the commit it ran on (``+dirty`` when the tree had
changes; run it on a commit that is on main, or say in ``ran_on`` which main commit holds the same
code, as a rebased branch's id is not main's), the date, the exit status, wall and CPU time (the command and every process it waited for),
the 1-minute load average before and after, and everything it printed (stdout then stderr).

    python -m docsite.records attach NAME reports/x/signoff.json   # a verify run's figures per condition

A page quotes it with a ```text block preceded by ``<!-- record: NAME -->``: every line of the
block must be a line of the record's output, in order, numbers at the digits quoted (the same
check as a command's output, ``docsite/outputs.py``), and the page must name the record's commit.
Sentences that read the block mark their numbers ``block:`` (``docsite/figures.py``), figures of the
record's own fields ``record:docs/records/NAME.json::KEY``. ``tests/test_docs_figures.py`` checks
every such block; a record is right for its commit, and the page says which.
"""
from __future__ import annotations

import json
import os
import re
import resource
import subprocess
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

from docsite import outputs

ROOT = Path(__file__).resolve().parents[1]
FOLDER = ROOT / "docs" / "records"
#: ``<!-- record: NAME -->`` (and other notes) right above a ```text block
BLOCK = re.compile(r"((?:<!--[^\n]*-->\n)+)```text\n(.*?)\n```", re.S)
NOTE = re.compile(r"<!--\s*record:\s*([A-Za-z0-9_.-]+)\s*-->")


def _commit() -> str:
    git = ["git", "-C", str(ROOT)]
    head = subprocess.run(git + ["rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(git + ["status", "--porcelain", "--untracked-files=no"], capture_output=True,
                           text=True).stdout.strip()
    return head + ("+dirty" if dirty else "")


def run(name: str, command: list[str]) -> dict:
    """Run ``command`` and store its record as ``docs/records/NAME.json``."""
    prelude = (f'pixelkit() {{ "{sys.executable}" -m pixelkit "$@"; }}\n'
               f'python() {{ "{sys.executable}" "$@"; }}\n')
    line, commit = " ".join(command), _commit()
    before, t0, c0 = os.getloadavg()[0], time.monotonic(), resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run(["bash", "-c", prelude + line], cwd=ROOT, capture_output=True, text=True,
                       env={**os.environ, "PIXELKIT_PROGRESS": "0"})
    c1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    rec = {"command": line, "commit": commit,
           "date": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"), "exit": p.returncode,
           "wall_s": round(time.monotonic() - t0, 1),
           "cpu_s": round(c1.ru_utime + c1.ru_stime - c0.ru_utime - c0.ru_stime, 1),
           "load": [round(before, 1), round(os.getloadavg()[0], 1)], "cores": os.cpu_count(),
           "output": p.stdout + p.stderr}
    FOLDER.mkdir(parents=True, exist_ok=True)
    (FOLDER / f"{name}.json").write_text(json.dumps(rec, indent=1) + "\n")
    return rec


def _sig(x, n=6):
    return float(f"{x:.{n}g}") if isinstance(x, (int, float)) and not isinstance(x, bool) else x


def attach(name: str, signoff: Path) -> dict:
    """Add the per-condition figures of a verify run's ``signoff.json`` to its record ``NAME`` (the same
    run: its ``--out``), in each spec's unit, so a page can quote a condition's figure, a spec's
    failing conditions or yield with ``record:docs/records/NAME.json::signoff.KEY`` marks."""
    from pixelkit.verify.figures import FIGURES, shown
    f = FOLDER / f"{name}.json"
    rec, d = json.loads(f.read_text()), json.loads(Path(signoff).read_text())
    units = {r["spec"]: (r["figure"], r["unit"]) for r in d["rows"]}
    conditions = {}
    for c in d["conditions"]:
        row = {spec: _sig(shown(c["figures"][fig], unit, FIGURES[fig].dim))
               for spec, (fig, unit) in units.items() if c["figures"].get(fig) is not None}
        pixel = d["raw"].get(c["label"], {}).get("pixel", {})
        for i, kind in enumerate(("primary", "secondary")):
            if "swing_V" in pixel:
                row[f"swing_V_{kind}"] = _sig(pixel["swing_V"][i])
            if "cg_out_V_per_e" in pixel:
                row[f"cg_out_uV_per_e_{kind}"] = _sig(pixel["cg_out_V_per_e"][i] * 1e6)
        conditions[c["label"]] = row
    rows = {r["spec"]: {"unit": r["unit"], "worst": r["worst"], "value": _sig(r["value"]),
                        "nominal": _sig(r.get("nominal")), "margin_pct": _sig(r["margin_pct"]),
                        "failing": len(r.get("failing_at") or []), "conditions": r["conditions"],
                        "yield": {k: _sig(v) if not isinstance(v, list) else [_sig(x) for x in v]
                                  for k, v in (r.get("yield") or {}).items() if k != "sigma_si"}}
            for r in d["rows"]}
    rec["signoff"] = {"from": "the run's signoff.json (--out)", "wall_s": _sig(d["wall_s"], 5),
                      "mc": {k: d["mc"].get(k) for k in ("samples", "planned", "seed", "condition")},
                      "rows": rows, "conditions": conditions,
                      "power": {"chip_W": _sig(d["power"]["chip_W"]),
                                "chip_blocks_W": {k: _sig(v) for k, v in d["power"]["chip_blocks_W"].items()},
                                "estimate_chip_blocks_W": {k: _sig(v) for k, v in
                                                           d["power"]["estimate"]["chip_blocks_W"].items()},
                                "pixel_W": _sig(d["power"]["pixel_W"]), "column_W": _sig(d["power"]["column_W"]),
                                **{k: _sig(v) for k, v in d["power"].items() if k.endswith("_s")}}}
    f.write_text(json.dumps(rec, indent=1) + "\n")
    return rec


def check(files) -> tuple[list[str], int]:
    """([every problem: page, record, line], how many record blocks were checked) of ``files``."""
    bad, n = [], 0
    for page in files:
        text = page.read_text()
        for m in BLOCK.finditer(text):
            note = NOTE.search(m.group(1))
            if not note:
                continue
            n += 1
            where = f"{page.name}:{text[:m.start(2)].count(chr(10)) + 1}"
            f = FOLDER / f"{note[1]}.json"
            if not f.is_file():
                bad.append(f"{where}: no record docs/records/{note[1]}.json (python -m docsite.records run {note[1]} -- CMD)")
                continue
            rec = json.loads(f.read_text())
            problems, _ = outputs.compare(m.group(2), rec["output"], [])
            bad += [f"{where}: record {note[1]} ({rec['commit']}, {rec['date']}): {p}" for p in problems]
            if rec["commit"].split("+")[0] not in text:
                bad.append(f"{where}: the page does not name the record's commit {rec['commit']}")
    return bad, n


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "attach":
        attach(sys.argv[2], Path(sys.argv[3]))
        sys.exit(print(f"docs/records/{sys.argv[2]}.json: signoff figures of {sys.argv[3]} added"))
    if len(sys.argv) < 4 or sys.argv[1] != "run" or sys.argv[3] != "--":
        sys.exit("usage: python -m docsite.records run NAME -- COMMAND ...")
    r = run(sys.argv[2], sys.argv[4:])
    print(f"docs/records/{sys.argv[2]}.json: exit {r['exit']}, {r['wall_s']} s wall, {r['cpu_s']} s CPU, "
          f"at {r['commit']}, load {r['load'][0]} - {r['load'][1]}")
