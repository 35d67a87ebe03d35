"""Seeded fuzz of the gap CSV: every column x a corpus of hostile values, in one row and in all rows.

The base is a committed virtual-silicon case (SPICE-made, ``tests/gapcases.py``).

Asserts: no internal error (only the kit's one-line data errors), and no
success with a non-finite number anywhere in the answer (checked by a strict
JSON encoding). Mutations that pass validation are diagnosed (a seeded sample,
to bound the time); all are validated.
"""
import csv
import io
import json

import numpy as np
import pytest

import gapcases
from pixelkit.errors import PixelkitError
from pixelkit.gap.data import validate

CORPUS = ["", " ", "nan", "NaN", "inf", "-inf", "1e300", "-1e300", "1e-300", "-1", "0", "1_0", "0x1A", "abc",
          "1e", "\u0661\u0662", "1\u20282", "+5", "3.0", "99999999999999999999", "1,5", "\x00"]


@pytest.fixture(scope="module")
def nominal(thesis_read_design):
    from pixelkit.gap.store import load_nominal
    return load_nominal(thesis_read_design)


@pytest.fixture(scope="module")
def base():
    """A committed SPICE-made case (stray light on the storage node, ``tests/gapcases.py``)."""
    rows = gapcases.rows(gapcases.ids("gse")[0])
    return list(rows[0]), rows


def _roundtrip(header, rows):
    """Through the csv module, as a file would be read."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, header)
    w.writeheader()
    w.writerows(rows)
    r = csv.DictReader(io.StringIO(buf.getvalue()))
    return r.fieldnames, list(r)


def test_fuzz_every_column(base, thesis_read_design, nominal):
    from pixelkit.gap.diagnose import diagnose
    header, rows = base
    rng = np.random.default_rng(2024)
    passed, n = [], 0
    for col in header:
        for value in CORPUS:
            for scope in ("one", "all"):
                mutated = [dict(r) for r in rows]
                targets = range(len(rows)) if scope == "all" else [int(rng.integers(len(rows)))]
                for i in targets:
                    mutated[i][col] = value
                h, rr = _roundtrip(header, mutated)
                n += 1
                try:
                    table = validate(h, rr, thesis_read_design, True, "fuzz.csv")
                except PixelkitError as e:
                    assert str(e).startswith("fuzz.csv") and "\n" not in str(e).split(": ", 1)[0]
                    continue
                passed.append((col, value, scope, table))
    assert n == len(header) * len(CORPUS) * 2
    order = rng.permutation(len(passed))[:10]
    for k in order:
        col, value, scope, table = passed[k]
        try:
            d = diagnose(thesis_read_design, table, nominal)
        except PixelkitError:
            continue   # a degenerate set refused before naming an effect
        json.dumps(d, allow_nan=False, default=float)   # no NaN / infinity in a successful answer


def test_fuzz_cli_sample(tmp_path, base, cli):
    """A few mutated files through the command line: exit 2 with one line, or 0 with finite JSON."""
    header, rows = base
    from conftest import THESIS_READ
    for k, (col, value) in enumerate([("i_ph_A", "1e300"), ("row", "1_0"), ("v_std_V", "-1"), ("n_avg", "0"),
                                      ("temp_C", "nan"), ("probe", "AFE ")]):
        mutated = [dict(r) for r in rows]
        mutated[3][col] = value
        p = tmp_path / f"f{k}.csv"
        with open(p, "w", newline="") as fh:
            w = csv.DictWriter(fh, header)
            w.writeheader()
            w.writerows(mutated)
        code, out, err = cli("gap", "diagnose", THESIS_READ, "--measured", p, "--json")
        assert code in (0, 2) and "Traceback" not in err, (col, value, err)
        if code == 0:
            json.loads(out, parse_constant=lambda c: pytest.fail(f"{c} in the answer"))
        else:
            assert col in json.loads(out)["error"]


@pytest.mark.parametrize("opt,value", [("--gain-sd", "0"), ("--gain-sd", "-0.01"), ("--gain-sd", "nan"),
                                       ("--offset-sd", "0"), ("--offset-sd", "2"), ("--offset-sd", "1e")])
def test_bench_calibration_out_of_range_is_named(tmp_path, base, cli, opt, value):
    """A stated calibration must be a positive standard deviation within the set-up's plausible range: exit 2
    naming the option before anything is fitted."""
    from conftest import THESIS_READ
    header, rows = base
    p = tmp_path / "m.csv"
    with open(p, "w", newline="") as fh:
        w = csv.DictWriter(fh, header)
        w.writeheader()
        w.writerows(rows)
    code, out, err = cli("gap", "diagnose", THESIS_READ, "--measured", p, opt, value, "--json")
    assert code == 2 and "Traceback" not in err
    assert opt in json.loads(out)["error"]
