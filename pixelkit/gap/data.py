"""Measured-data and conditions files: reading and validation, reported by row and column.

One row per operating point. Required columns (units in the names):
``array`` (primary|secondary), ``row``, ``col`` (0-based within the array),
``i_ph_A``, ``t_int_s``, ``t_wait_s``, ``temp_C``, ``probe`` (pixel|afe), and in
measured files ``v_V``. Optional: ``v_std_V``, ``n_avg``, ``vdd_V``, ``f_read_Hz``,
``i_ph_prev_A`` (the same pixel's photocurrent in the previous frame, for lag).
Any other column is carried along untouched. Nothing is dropped silently: every
problem is listed with its row (1-based data line) and column.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import PixelkitError

REQUIRED = ("array", "row", "col", "i_ph_A", "t_int_s", "t_wait_s", "temp_C", "probe")
OPTIONAL = ("v_std_V", "n_avg", "vdd_V", "f_read_Hz", "i_ph_prev_A")
NUMERIC = ("row", "col", "i_ph_A", "t_int_s", "t_wait_s", "temp_C", "v_V") + OPTIONAL
# quantities whose unit suffix a user may have got wrong: stem -> the expected column
_STEMS = {"i_ph": "i_ph_A", "t_int": "t_int_s", "t_wait": "t_wait_s", "temp": "temp_C", "v": "v_V",
          "v_std": "v_std_V", "vdd": "vdd_V", "f_read": "f_read_Hz", "i_ph_prev": "i_ph_prev_A"}


class DataError(PixelkitError):
    def __init__(self, source: str, problems: list[str]):
        self.problems = problems
        more = f" (and {len(problems) - 20} more)" if len(problems) > 20 else ""
        super().__init__(f"{source}: {len(problems)} problem(s): " + "; ".join(problems[:20]) + more)


@dataclass
class Table:
    """Columns as numpy arrays (numeric) or lists (text), in file order."""
    columns: dict
    source: str

    def __len__(self):
        return len(self.columns["array"])

    def num(self, name):
        return self.columns[name]

    def subset(self, mask) -> "Table":
        idx = np.nonzero(mask)[0]
        cols = {k: (v[idx] if isinstance(v, np.ndarray) else [v[i] for i in idx]) for k, v in self.columns.items()}
        return Table(cols, self.source)


def read_table(path: str | Path, design, measured: bool) -> Table:
    path = Path(path)
    if not path.is_file():
        raise DataError(str(path), ["file not found"])
    with open(path, newline="") as fh:
        reader = csv.DictReader(fh)
        header = reader.fieldnames or []
        rows = list(reader)
    return validate(header, rows, design, measured, str(path))


def validate(header, rows, design, measured: bool, source: str) -> Table:
    problems = []
    need = REQUIRED + (("v_V",) if measured else ())
    for col in need:
        if col not in header:
            stem = col.rsplit("_", 1)[0] if col not in ("array", "row", "col", "probe") else col
            wrong = [h for h in header if h.rsplit("_", 1)[0] == stem and h != col]
            hint = f" (found '{wrong[0]}': wrong unit, expected '{col}')" if wrong else ""
            problems.append(f"missing column '{col}'{hint}")
    if problems:
        raise DataError(source, problems)
    cols = {h: [] for h in header}
    for r in rows:
        for h in header:
            cols[h].append(r.get(h))
    out = {}
    for h in header:
        if h in NUMERIC:
            vals = np.full(len(rows), np.nan)
            for i, txt in enumerate(cols[h]):
                if txt is None or txt.strip() == "":
                    if h in need:
                        problems.append(f"row {i + 1}, column '{h}': empty")
                    continue
                try:
                    x = float(txt)
                except ValueError:
                    problems.append(f"row {i + 1}, column '{h}': '{txt}' is not a number")
                    continue
                if not math.isfinite(x):
                    problems.append(f"row {i + 1}, column '{h}': {txt} (NaN or infinite)")
                vals[i] = x
            out[h] = vals
        else:
            out[h] = [(v or "").strip() for v in cols[h]]
    n_rows = {"primary": design.primary.rows, "secondary": design.secondary.rows}
    n_cols = {"primary": design.primary.cols, "secondary": design.secondary.cols}
    for i in range(len(rows)):
        arr, probe = out["array"][i], out["probe"][i]
        if arr not in n_rows:
            problems.append(f"row {i + 1}, column 'array': '{arr}' (allowed: primary, secondary)")
            continue
        if probe not in ("pixel", "afe"):
            problems.append(f"row {i + 1}, column 'probe': '{probe}' (allowed: pixel, afe)")
        for name, limit in (("row", n_rows[arr]), ("col", n_cols[arr])):
            v = out[name][i]
            if math.isfinite(v) and not (v == int(v) and 0 <= v < limit):
                problems.append(f"row {i + 1}, column '{name}': {v:g} is outside the {arr} array "
                                f"(0..{limit - 1}): the design cannot simulate it")
        for name in ("i_ph_A", "t_int_s", "t_wait_s"):
            v = out[name][i]
            if math.isfinite(v) and v < 0:
                problems.append(f"row {i + 1}, column '{name}': {v:g} is negative")
        t = out["temp_C"][i]
        if math.isfinite(t) and not -60 <= t <= 200:
            problems.append(f"row {i + 1}, column 'temp_C': {t:g} is outside -60..200 degC")
        if math.isfinite(out["t_int_s"][i]) and out["t_int_s"][i] == 0:
            problems.append(f"row {i + 1}, column 't_int_s': zero integration time")
    if problems:
        raise DataError(source, problems)
    return Table(out, source)


def write_table(table: Table, path: str | Path, extra: dict) -> Path:
    """Write ``table`` plus ``extra`` columns to CSV, atomically."""
    import io

    from ..fileio import write_atomic
    cols = dict(table.columns)
    cols.update(extra)
    buf = io.StringIO()
    w = csv.writer(buf)
    names = list(cols)
    w.writerow(names)
    for i in range(len(table)):
        w.writerow([_fmt(cols[n][i]) for n in names])
    return write_atomic(path, buf.getvalue())


def _fmt(v):
    if isinstance(v, (float, np.floating)):
        return "" if not math.isfinite(v) else f"{float(v):.9g}"
    return v
