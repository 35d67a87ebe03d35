"""The committed virtual-silicon cases (``pixelkit/gap/silicon_cases``) as test data.

Every case there was made by ngspice with the effect inserted as circuit
elements (``pixelkit/gap/silicon.py``), never by the effect library the fitter
uses: the gap tests take their measured data from here.
"""
import csv
import json
from pathlib import Path

CASES = Path(__file__).resolve().parents[1] / "pixelkit" / "gap" / "silicon_cases"


def truths() -> dict:
    return json.loads((CASES / "truth.json").read_text())


def rows(cid: str) -> list[dict]:
    with open(CASES / "cases.csv", newline="") as fh:
        return [{k: v for k, v in r.items() if k != "case"} for r in csv.DictReader(fh) if r["case"] == cid]


def ids(circuit: str) -> list[str]:
    """Case ids whose inserted circuit element is ``circuit`` (truth.json), in file order."""
    return [c for c, t in truths().items() if t["circuit"] == circuit]


def write_csv(cid: str, path: Path, drop=()) -> Path:
    """The case as a measured CSV, as a user would give it (optionally without some columns)."""
    rr = rows(cid)
    keys = [k for k in rr[0] if k not in drop]
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rr)
    return path
