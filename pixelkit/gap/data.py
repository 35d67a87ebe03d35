"""Measured-data and conditions files: reading and validation, reported by row and column.

One row per operating point. Required columns (units in the names):
``array`` (primary|secondary), ``row``, ``col`` (0-based within the array),
``i_ph_A``, ``t_int_s``, ``t_wait_s``, ``temp_C``, ``probe`` (pixel|afe), and in
measured files ``v_V``. Optional: ``v_std_V``, ``n_avg``, ``vdd_V``, ``f_read_Hz``,
``i_ph_prev_A`` (the same pixel's photocurrent in the previous frame, for lag).
Any other column is carried along untouched. Nothing is dropped silently: every
problem is listed with its row (1-based data line) and column. ``row``, ``col``
and ``n_avg`` are integers written as digits only (``1_0`` and ``1e1`` are
refused); a row with more fields than the header, a duplicated column name, a
file that is not UTF-8 are errors. ``v_std_V`` must be >= 0, ``n_avg`` >= 1.

``validate`` is the one validation of every quantity, shared by ``gap predict``
(conditions) and ``gap diagnose`` / ``plan`` (measured rows): besides the above,
times in 0 .. 10 s (the longest integration a design allows), photocurrents
(this frame's and the previous one's) >= 0 and filling the array's full well
(analytic model) at most 100 times over t_int.

``check_degenerate`` refuses, before any effect is named, a measured set that
cannot support a diagnosis: fewer rows than the candidates' parameters need, a
constant measured value, mostly duplicated rows, a level outside the supply
rails.
"""
from __future__ import annotations

import csv
import io
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import PixelkitError

REQUIRED = ("array", "row", "col", "i_ph_A", "t_int_s", "t_wait_s", "temp_C", "probe")
OPTIONAL = ("v_std_V", "n_avg", "vdd_V", "f_read_Hz", "i_ph_prev_A")
INTEGER = ("row", "col", "n_avg")
_INT = re.compile(r"^\s*[0-9]+\s*$")
NUMERIC = ("row", "col", "i_ph_A", "t_int_s", "t_wait_s", "temp_C", "v_V") + OPTIONAL
# quantities whose unit suffix a user may have got wrong: stem -> the expected column
_STEMS = {"i_ph": "i_ph_A", "t_int": "t_int_s", "t_wait": "t_wait_s", "temp": "temp_C", "v": "v_V",
          "v_std": "v_std_V", "vdd": "vdd_V", "f_read": "f_read_Hz", "i_ph_prev": "i_ph_prev_A"}


#: A photocurrent that fills the well more than this many times over t_int is beyond physical range.
MAX_WELLS = 100.0
#: Longest integration or wait time of a row (s): the longest integration a design allows (design.Subpixel).
MAX_TIME_S = 10.0


def full_wells(design) -> dict:
    """Full-well charge (C) of each array from the analytic model (the bound of the photocurrent check)."""
    from ..constants import Q
    from ..physics.subpixel import figures
    return {a: figures(design, a)["fwc_e"] * Q for a in ("primary", "secondary")}


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
    header, rows, source = read_rows(path, measured)
    return validate(header, rows, design, measured, source)


def numeric_column(name, texts, required, integer, problems):
    """The column ``name``'s cells (text or None) as floats, NaN where empty; each bad cell (empty in a
    required column, not a number, not a whole number where ``integer``, NaN or infinite) appended to
    ``problems`` as 'row N, column NAME: ...'."""
    vals = np.full(len(texts), np.nan)
    for i, txt in enumerate(texts):
        if txt is None or txt.strip() == "":
            if required:
                problems.append(f"row {i + 1}, column '{name}': empty")
            continue
        if integer and not _INT.match(txt):
            problems.append(f"row {i + 1}, column '{name}': '{txt}' is not a whole number (digits only)")
            continue
        try:
            x = float(txt)
        except ValueError:
            problems.append(f"row {i + 1}, column '{name}': '{txt}' is not a number")
            continue
        if not math.isfinite(x):
            problems.append(f"row {i + 1}, column '{name}': {txt} (NaN or infinite)")
        vals[i] = x
    return vals


def temperature_problem(i: int, t: float) -> list:
    """[the problem of row ``i``'s die temperature ``t`` (degC) outside -60..200 degC] or []."""
    if math.isfinite(t) and not -60 <= t <= 200:
        return [f"row {i + 1}, column 'temp_C': {t:g} is outside -60..200 degC"]
    return []


def read_rows(path: str | Path, measured: bool) -> tuple[list, list, str]:
    """(header, rows as {column: text}, source) of a CSV table, read bounded; DataError listing every
    problem (not UTF-8, not CSV, a duplicated column, a row whose fields are not the header's)."""
    from ..readfile import FileRefused, read_bytes
    path = Path(path)
    try:
        blob = read_bytes(path, "--measured" if measured else "--conditions", "csv")
    except FileRefused as e:
        raise DataError(str(path), [f"{e.value} (expected {e.allowed})"]) from None
    try:
        lines = list(csv.reader(io.StringIO(blob.decode("utf-8-sig"), newline="")))
    except UnicodeDecodeError as e:
        raise DataError(str(path), [f"not UTF-8 text (byte {e.start}: {e.reason})"]) from None
    except csv.Error as e:
        raise DataError(str(path), [f"cannot be read as CSV: {e}"]) from None
    if not lines:
        raise DataError(str(path), ["empty file (no header)"])
    header = [h.strip() for h in lines[0]]
    dup = sorted({h for h in header if header.count(h) > 1})
    if dup:
        raise DataError(str(path), [f"column '{d}' appears {header.count(d)} times" for d in dup])
    problems, rows = [], []
    for k, fields in enumerate(lines[1:], 1):
        if not fields:
            continue
        if len(fields) != len(header):   # issue 44: a short row was read with its last columns empty
            what = "extra fields" if len(fields) > len(header) else \
                f"missing {', '.join(repr(h) for h in header[len(fields):][:3])}{'...' if len(header) - len(fields) > 3 else ''}"
            problems.append(f"row {k}: {len(fields)} fields, the header has {len(header)} ({what}; every row has "
                            "exactly the header's fields, an empty value written as nothing between two commas)")
        rows.append(dict(zip(header, fields)))
    if problems:
        raise DataError(str(path), problems)
    if not rows:
        raise DataError(str(path), ["no data rows (header only)"])
    return header, rows, str(path)


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
            out[h] = numeric_column(h, cols[h], h in need, h in INTEGER, problems)
        else:
            out[h] = [(v or "").strip() for v in cols[h]]
    wells = full_wells(design)
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
        for name in ("i_ph_A", "t_int_s", "t_wait_s", "i_ph_prev_A"):
            v = out[name][i] if name in out else math.nan
            if math.isfinite(v) and v < 0:
                problems.append(f"row {i + 1}, column '{name}': {v:g} is negative")
        for name in ("t_int_s", "t_wait_s"):
            v = out[name][i]
            if math.isfinite(v) and v > MAX_TIME_S:
                problems.append(f"row {i + 1}, column '{name}': {v:g} s is beyond {MAX_TIME_S:g} s (the longest "
                                "integration a design allows)")
        t_int = out["t_int_s"][i]
        for name in ("i_ph_A", "i_ph_prev_A"):
            v = out[name][i] if name in out else math.nan
            fill = float(v) * float(t_int) / wells[arr] if math.isfinite(v) and math.isfinite(t_int) else 0.0
            if fill > MAX_WELLS:
                times = f"{fill:.3g} times" if fill < 1e6 else "more than a million times"
                problems.append(f"row {i + 1}, column '{name}': {v:g} A fills the {arr} well {times} over "
                                f"t_int (beyond physical range, limit {MAX_WELLS:g} x)")
        if "v_std_V" in out and math.isfinite(out["v_std_V"][i]) and out["v_std_V"][i] < 0:
            problems.append(f"row {i + 1}, column 'v_std_V': {out['v_std_V'][i]:g} is negative (a standard deviation)")
        if "n_avg" in out and math.isfinite(out["n_avg"][i]) and out["n_avg"][i] < 1:
            problems.append(f"row {i + 1}, column 'n_avg': {out['n_avg'][i]:g} (allowed: 1 or more frames averaged)")
        for name in ("f_read_Hz", "vdd_V"):
            if name in out and math.isfinite(out[name][i]) and out[name][i] <= 0:
                problems.append(f"row {i + 1}, column '{name}': {out[name][i]:g} must be positive")
        problems += temperature_problem(i, out["temp_C"][i])
        if math.isfinite(out["t_int_s"][i]) and out["t_int_s"][i] == 0:
            problems.append(f"row {i + 1}, column 't_int_s': zero integration time")
    if problems:
        raise DataError(source, problems)
    return Table(out, source)




def check_degenerate(table: Table, X, nom, candidates) -> None:
    """Refuse a measured set that cannot support naming an effect (see the module docstring)."""
    problems = []
    y = table.num("v_V")
    n = len(y)
    from .effects import CORE, EFFECTS
    k_max = 2 + max([len(CORE[c][0]) if c in CORE else len(EFFECTS[c][0]) for c in candidates
                     if EFFECTS[c][1] is not None] or [0])
    need = max(12, 4 * k_max)
    if n < need:
        problems.append(f"{n} rows: too few for the candidates' parameters (need at least {need})")
    if n and np.ptp(y) == 0:
        problems.append(f"column 'v_V' is constant ({y[0]:g} V on every row): nothing to diagnose")
    keys = [tuple(_fmt(table.columns[c][i]) for c in table.columns) for i in range(n)]
    n_unique = len(set(keys))
    if n and n_unique < max(need, 0.5 * n):
        problems.append(f"only {n_unique} distinct rows of {n} (duplicated rows)")
    cond = [tuple(_fmt(table.columns[c][i]) for c in REQUIRED) for i in range(n)]
    if n and len(set(cond)) < need:
        problems.append(f"only {len(set(cond))} distinct operating points: too few for the candidates' parameters")
    top = float(X["vdd"].max()) + 0.5
    bad = np.nonzero((y < -0.5) | (y > top))[0]
    for i in bad[:5]:
        problems.append(f"row {i + 1}, column 'v_V': {y[i]:g} V is outside the supply rails (-0.5 .. {top:g} V)")
    if problems:
        raise DataError(table.source, problems)


def write_table(table: Table, path: str | Path, extra: dict) -> Path:
    """Write ``table`` plus ``extra`` columns to CSV, atomically."""
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
