"""Numbers the manual quotes from the kit, checked against the kit's current output.

A page marks each number it quotes from the kit with an HTML comment right after it (invisible
on the site, where the hook removes it, and on a repository host):

    read noise 408.9<!--fig quick:noise_budget::read noise at the column (e-)::primary--> e-

``quick:`` is the quick report of the reference design (``pixelkit report
designs/dual_pixel_revA.toml --quick``): ``TABLE::ROW::COLUMN`` a cell of its ``tables.json``
(the row by its first cell, the column by its heading), or ``checked::NAME`` a checked figure of
its ``summary.json``, ``data_SECTION.json::DOTTED`` a number of a section's data file
(``data_noise.json::spice.primary.fd_reset_V2``), or ``verdict::FIELD`` a number of its verdict (``passing``, ``specs``). A key may end with ``*SCALE`` (``*1e3``: V quoted in mV). The quoted
number must be the current value as printed to the same digits (401.9 stands for 401.85 -
401.95); ``~2%`` after the key allows a band instead (a figure that scatters).

    python -m docsite.figures REPORT_DIR            # list every quoted figure that moved (exit 1)
    python -m docsite.figures REPORT_DIR --update   # rewrite them from the report, same digits
    python -m docsite.figures                       # the marks that need no run (block, record, calc)

``tests/test_docs_figures.py`` runs the check on the session's quick report, so a figure that
moves fails the suite and names the page, the line and the command that rewrites it. New sources
(another design's report, a command's ``--json``) are one entry of ``SOURCES``.

Four sources need no run and are checked wherever the marks are (``LOCAL``):

- ``block:TEXT`` (``block:TEXT@L#N``): a number of a ```text block of the same page, the first (N-th)
  number after ``TEXT`` on the first (L-th) block line holding it; ``block:[PAGE.md]TEXT`` reads
  another docs page's blocks. The blocks of the pages the suite runs
  are checked against the command's output (``docsite/outputs.py``), so prose that reads a block is
  checked through it; on a page whose block is a dated record, the prose is held to the record.
- ``record:PATH::KEY``: a stored results file of the repository (JSON, ``KEY`` dotted, list items
  by index), which must say when and on what it was measured (``date`` and ``commit`` or ``head``
  at its top): a measurement a test cannot repeat (a benchmark, a full-grid sign-off); a record of a
  ``--json`` command reads into its output (``record:docs/records/NAME.json::output.KEY``).
- ``file:PATH::KEY``: a JSON data file of the repository that is an input, not a measurement (the
  truth a virtual chip was made with).
- ``input:PATH::KEY``: a value of a design or technology file (TOML, a quantity's number as written;
  a quoted part of the key may hold dots: ``close.knobs."afe.c11".min``)
  or JSON input; ``input:WHY`` (no ``::``) a stated input no file holds, not checked.
- ``default:DOTTED``: the design file schema's default of a field (``afe.supply_current``), SI.
- ``schema:DOTTED.META[.i]``: a field's metadata in the design schema (``schema:pixel.sf_bias.plausible.1``).
- ``const:pixelkit.MODULE.NAME[.KEY...]``: a constant of the kit's code (a limit, a bound), SI.
- ``cite:KEY``: a source document's value (``KEY`` of docs/bibliography.md), not the kit's: not checked.
- ``calc:EXPR``: a figure the sentence derives (a ratio, a difference), ``EXPR`` arithmetic
  (``+ - * / **``, ``abs min max``) over ``{SOURCE:KEY}`` references.

A key may not hold ``>`` (the site's hook removes ``<!--fig ...-->`` up to the first one).
"""
from __future__ import annotations

import ast
import json
import math
import operator
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
MARK = re.compile(r"(?P<num>" + NUMBER + r")<!--fig (?P<src>[a-z_][a-z0-9_]*):(?P<key>.+?)(?:\s*~(?P<tol>[0-9.]+)%)?-->")
#: a marker alone (the hook removes them from the site's pages)
ANY_MARK = re.compile(r"<!--fig [^>]*-->")


SPAN = re.compile(r"`[^`\n]*`")


def _outside_code(line: str):
    """The marks of ``line`` outside inline code spans (a page may show the syntax itself)."""
    spans = [m.span() for m in SPAN.finditer(line)]
    return [m for m in MARK.finditer(line) if not any(a <= m.start() < b for a, b in spans)]


def pages() -> list[Path]:
    return sorted((ROOT / "docs").glob("*.md")) + [ROOT / "README.md"]


def quick_source(report: Path):
    """The value of a ``quick:`` key in the report folder ``report``."""
    tables = json.loads((Path(report) / "tables.json").read_text())
    summary = json.loads((Path(report) / "summary.json").read_text())
    checked, verdict = summary["checked"], summary.get("verdict", {})

    def value(key: str) -> float:
        parts = key.split("::")
        if parts[0] == "checked":
            return float(checked[parts[1]]["value"])
        if parts[0] == "verdict":
            return float(verdict[parts[1]])
        if parts[0].startswith("data_") and parts[0].endswith(".json"):   # the report's section data
            data = json.loads((Path(report) / parts[0]).read_text())
            for part in parts[1].split("."):
                data = data[int(part)] if isinstance(data, list) else data[part]
            return float(data)
        table, row, col = parts
        t = tables[table]
        r = next(r for r in t["rows"] if str(r[0]) == row)
        return float(r[t["columns"].index(col)])
    return value


SOURCES = {"quick": quick_source}

#: fenced blocks of command output on a page
TEXT_BLOCK = re.compile(r"^```text\n(.*?)\n```", re.S | re.M)
NUMBER_RE = re.compile(NUMBER)


def _block_lines(text: str) -> list[str]:
    return [" ".join(line.split()) for b in TEXT_BLOCK.findall(text) for line in b.splitlines()]


def block_source(page_text: str):
    """The value of a ``block:`` key on the page whose text is ``page_text`` (``block:[PAGE.md]TEXT``:
    a block of another docs page, e.g. the dated record another page shows)."""
    here = _block_lines(page_text)

    def value(key: str) -> float:
        lines = here
        other = re.match(r"\[([\w.-]+\.md)\]", key)
        if other:
            lines, key = _block_lines((ROOT / "docs" / other[1]).read_text()), key[other.end():]
        text, _, nth = key.rpartition("#") if re.search(r"#\d+$", key) else (key, "", "1")
        text, _, which = text.rpartition("@") if re.search(r"@\d+$", text) else (text, "", "1")
        text = " ".join(text.split())
        holding = [line for line in lines if text in line]
        if len(holding) < int(which):
            raise LookupError(f"{len(holding)} text block line(s) of the page hold {text!r}")
        line = holding[int(which) - 1]
        after = line[line.index(text) + len(text):]
        return float(NUMBER_RE.findall(after)[int(nth) - 1])
    return value


def _json_value(key: str, dated: bool) -> float:
    path, _, dotted = key.partition("::")
    f = (ROOT / path).resolve()
    if ROOT not in f.parents:
        raise KeyError(path)
    data = json.loads(f.read_text())
    if dated and ("date" not in data or not ({"commit", "head"} & set(data))):
        raise ValueError(f"{path} does not say when and on what it was measured (date, commit)")
    for part in _parts(dotted):
        if isinstance(data, str):           # a record's output that is JSON (a command's --json)
            data = json.loads(data)
        data = data[int(part)] if isinstance(data, list) else data[part]
    return float(data)


def input_value(key: str) -> float:
    """The value of an ``input:`` key: ``PATH::dotted.key`` of a design, technology or data file of
    the repository (TOML or JSON; a quantity string such as ``"400 nA"`` gives its number as written),
    or, with no ``::``, a stated input no file holds (a method's criterion, a test's band), not checked."""
    if "::" not in key:
        raise Unchecked(key)
    path, _, dotted = key.partition("::")
    f = (ROOT / path).resolve()
    if ROOT not in f.parents:
        raise KeyError(path)
    if f.suffix == ".toml":
        import tomllib
        data = tomllib.loads(f.read_text())
    else:
        data = json.loads(f.read_text())
    for part in _parts(dotted):
        data = data[int(part)] if isinstance(data, list) else data[part]
    return float(NUMBER_RE.match(data.strip())[0]) if isinstance(data, str) else float(data)


def _parts(dotted: str) -> list[str]:
    """``a."b.c".0`` -> ``["a", "b.c", "0"]`` (a quoted part may hold dots, as a TOML key may)."""
    return [p.strip('"') for p in re.findall(r'"[^"]*"|[^.]+', dotted)]


def default_value(key: str) -> float:
    """The value of a ``default:`` key: the design file schema's default of a field (``afe.supply_current``,
    ``verify.confidence``), in SI (``*1e6``: A quoted in uA), as the loader applies it."""
    import dataclasses
    from pixelkit.design import Design
    cls, value, parts = Design, None, key.split(".")
    while parts:
        part = parts.pop(0)
        f = {f.name: f for f in dataclasses.fields(cls)}[part]
        if f.metadata.get("kind") == "table":
            cls = f.metadata["cls"]
            continue
        if parts:                               # schema: a field's metadata (plausible.0, le, ...)
            value = f.metadata
            for m in parts:
                value = value[int(m)] if isinstance(value, (list, tuple)) else value[m]
            break
        value = f.default if f.default is not dataclasses.MISSING else f.default_factory()
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        raise LookupError(f"{key} has no numeric default")
    return float(value)


def const_value(key: str) -> float:
    """The value of a ``const:`` key: a constant of the kit's code, ``pixelkit.MODULE.NAME`` then
    dotted keys or indices into it (``const:pixelkit.verify.figures.PLAUSIBLE.power.1``; a function's
    parameter gives its default: ``const:pixelkit.spice.scratch.watch_parent.interval``): a limit or
    a stated bound the code itself holds, so the page fails when the code changes it."""
    import importlib
    parts = key.split(".")
    if parts[0] != "pixelkit":
        raise LookupError(f"{key}: only constants of pixelkit")
    for n in range(len(parts), 0, -1):
        try:
            data, rest = importlib.import_module(".".join(parts[:n])), parts[n:]
            break
        except ImportError:
            continue
    for part in rest:
        if isinstance(data, (list, tuple)):
            data = data[int(part)]
        elif isinstance(data, dict):
            data = data[part]
        elif callable(data) and not isinstance(data, type) and not hasattr(data, part):
            import inspect                      # a function's parameter: its default
            data = inspect.signature(data).parameters[part].default
        else:
            data = getattr(data, part)
    if not isinstance(data, (int, float)) or isinstance(data, bool):
        raise LookupError(f"{key} is not a number")
    return float(data)


class Unchecked(Exception):
    """A mark that declares a number not the kit's output (a cited source's value, a stated input)."""


def cite_value(key: str) -> float:
    """``cite:KEY`` (``cite:KEY::where``): a value of a source document, which docs/bibliography.md must
    define; compared with the kit by the sentence, not checked against it."""
    name = key.split("::")[0]
    if f"[{name}]" not in (ROOT / "docs" / "bibliography.md").read_text():
        raise LookupError(f"[{name}] is not a key of docs/bibliography.md")
    raise Unchecked(key)


def dated_source(page_text: str):
    """``dated:COMMIT``: a figure of a past run the page quotes as history (a study on copies of a
    design, a benchmark before a change) whose output was not stored: not checked against the kit, but
    the page must name the commit it was measured at (outside the marks), so the reader sees its age;
    a figure of the kit as it is now is never ``dated:``."""
    plain = ANY_MARK.sub("", page_text)

    def value(key: str) -> float:
        if not re.fullmatch(r"[0-9a-f]{7,40}", key):
            raise ValueError(f"dated:{key}: not a commit id (7 - 40 hex digits)")
        if not re.search(r"\b" + key[:7], plain):
            raise LookupError(f"the page does not name the commit {key}")
        raise Unchecked(key)
    return value


def record_value(key: str) -> float:
    """The value of a ``record:`` key (``PATH::dotted.key``) in a stored results file (dated)."""
    return _json_value(key, dated=True)


def file_value(key: str) -> float:
    """The value of a ``file:`` key (``PATH::dotted.key``) in a data file of the repository (an input:
    the truth a virtual chip was made with, a close record)."""
    return _json_value(key, dated=False)


_OPS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
        ast.Pow: operator.pow, ast.USub: operator.neg, ast.UAdd: operator.pos}
_FUNCS = {"abs": abs, "min": min, "max": max}
REF = re.compile(r"\{([a-z_][a-z0-9_]*):([^{}]+)\}")


def calc_source(getters):
    """The value of a ``calc:`` key: arithmetic over ``{SOURCE:KEY}`` references to ``getters``."""
    def value(key: str) -> float:
        refs = []

        def ref(m):
            refs.append(getters[m[1]](m[2]))
            return f"_{len(refs) - 1}"

        def ev(n):
            if isinstance(n, ast.Expression):
                return ev(n.body)
            if isinstance(n, ast.Constant) and isinstance(n.value, (int, float)):
                return n.value
            if isinstance(n, ast.Name) and n.id.startswith("_"):
                return refs[int(n.id[1:])]
            if isinstance(n, ast.BinOp) and type(n.op) in _OPS:
                return _OPS[type(n.op)](ev(n.left), ev(n.right))
            if isinstance(n, ast.UnaryOp) and type(n.op) in _OPS:
                return _OPS[type(n.op)](ev(n.operand))
            if isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id in _FUNCS:
                return _FUNCS[n.func.id](*[ev(a) for a in n.args])
            raise ValueError(f"not arithmetic: {ast.dump(n)[:60]}")
        return float(ev(ast.parse(REF.sub(ref, key), mode="eval")))
    return value


def _with_local(getters: dict, page_text: str) -> dict:
    """``getters`` plus the sources that need no run: this page's blocks, stored records, calc."""
    out = {**getters, "block": block_source(page_text), "record": record_value, "file": file_value,
           "input": input_value, "cite": cite_value, "default": default_value, "schema": default_value,
           "const": const_value, "dated": dated_source(page_text)}
    out["calc"] = calc_source(out)
    return out


#: the sources every check has (no run needed)
LOCAL = ("block", "record", "file", "calc", "input", "cite", "default", "schema", "const", "dated")
#: sources checked by their own tests, not from the quick report: ``p4t`` (``pixelkit simulate
#: designs/pixel4t_gf180.toml --json``, dotted keys into its JSON; tests/test_pixel4t.py);
#: ``pl`` (the GF180 dual pixel's schematic and post-layout views, ``VIEW.ARRAY.FIGURE``: C_FD, C_PD,node, the
#: column line, CG_out(0) model and SPICE charge step; tests/test_post_layout.py); ``xs`` (the extraction's
#: term of a test structure, ``SET.NAME`` in F: docs/post-layout.md's structure tables;
#: tests/test_extraction_structures.py); ``afen`` (the AFE noise's closed forms over SPICE's - 1 in %, ``CASE``:
#: docs/noise-camera.md; tests/test_afe_noise.py); ``afeg`` (the AFE gain error measured and predicted per op-amp
#: gain: docs/pixel-model.md, docs/verify.md; tests/test_afe.py); ``stl`` (settling at ss 85 degC -10 %: the
#: 9-row bright cycle and verify's 2-row figure, docs/verify.md; tests/test_settling.py); ``nzf`` (the column 1/f
#: model below ngspice's at 400 nA and at the design's load, docs/noise-camera.md, timing-and-settling.md;
#: tests/test_noise.py); ``sf`` (the source follower's EKV gain against SPICE's, its column noise: docs/source-follower.md;
#: tests/test_sf.py); ``wdr`` (the WDR pixel's noise floor by part, from the model's and from SPICE's dark current:
#: docs/dark-current.md; tests/test_wdr.py); ``gss`` (the gap diagnosis's stratified sample of the committed SPICE
#: cases as the default suite diagnoses it: docs/gap-diagnosis.md; tests/test_gap_silicon.py); ``lim`` (the spec limits'
#: derivations on ngspice's device charges: docs/revisions.md; tests/test_spec_limits.py)
OTHER_SOURCES = ("p4t", "pl", "xs", "stk", "afen", "afeg", "stl", "nzf", "sf", "wdr", "gss", "lim", "ppw", "ppd", "ppv")


def _digits(text: str) -> float:
    """Half a unit of the last digit ``text`` is printed to (the rounding it stands for)."""
    mant, _, exp = text.lower().lstrip("+-").partition("e")
    decimals = len(mant.split(".")[1]) if "." in mant else 0
    return 0.5 * 10.0 ** (-decimals + (int(exp) if exp else 0))


def _printed(value: float, like: str) -> str:
    """``value`` printed the way ``like`` is (same decimals or exponent form)."""
    mant, _, exp = like.lower().lstrip("+-").partition("e")
    decimals = len(mant.split(".")[1]) if "." in mant else 0
    if exp:
        e = int(exp)
        s = f"{value / 10 ** e:.{decimals}f}e{exp}"
    else:
        s = f"{value:.{decimals}f}"
    return ("+" if like.startswith("+") and value >= 0 else "") + s


def check(report: Path, files=None, getters=None) -> tuple[list[dict], int]:
    """([every quoted figure that does not match the report], how many were checked). ``getters``
    ({source: key -> value}) instead of the report's: a test that holds another source's output (the
    4T pixel's experiment, ``tests/test_pixel4t.py``) checks the marks of that source; marks of a
    source not in ``getters`` are another check's and are skipped."""
    getters = getters if getters is not None else {name: make(report) for name, make in SOURCES.items()}
    bad, n = [], 0
    for page in files or pages():
        here = _with_local(getters, page.read_text())
        for lineno, line in enumerate(page.read_text().splitlines(), 1):
            for m in _outside_code(line):
                if _elsewhere(m, getters):
                    continue
                n += 1
                key, src, quoted = m["key"], m["src"], m["num"]
                try:
                    value = _value(here, src, key)
                except Unchecked:
                    continue
                except (LookupError, StopIteration, ValueError, TypeError, ZeroDivisionError,
                        SyntaxError, FileNotFoundError, json.JSONDecodeError, AttributeError, ImportError) as exc:
                    bad.append({"page": page.name, "line": lineno, "key": f"{src}:{key}", "quoted": quoted,
                                "value": None, "why": f"no such figure ({type(exc).__name__}{': ' + str(exc) if type(exc) in (ValueError, LookupError) else ''})"})
                    continue
                tol = abs(value) * float(m["tol"]) / 100 if m["tol"] else _digits(quoted) * (1 + 1e-9)
                if not math.isfinite(value) or abs(float(quoted) - value) > tol:
                    bad.append({"page": page.name, "line": lineno, "key": f"{src}:{key}", "quoted": quoted,
                                "value": value, "now": _printed(value, quoted) if math.isfinite(value) else None})
        text = SPAN.sub("", page.read_text())
        unmarked = len(ANY_MARK.findall(text)) - len(MARK.findall(text))
        if unmarked:
            bad.append({"page": page.name, "line": 0, "key": "-", "quoted": "-", "value": None,
                        "why": f"{unmarked} marker(s) not right after a number or not of the form "
                               "NUMBER<!--fig SOURCE:KEY-->"})
    return bad, n


def hold(pages, source: str, data) -> list[str]:
    """The page check of a test that computes ``source``'s figures itself: ``data`` (nested dicts and lists read by
    a dotted key, or a function of the key) against every ``source:`` mark of ``pages``; with
    ``PIXELKIT_DOCS_REWRITE=1`` the quoted figures are rewritten first. The stale ones, as ``page:line`` messages."""
    import os

    def value(key: str) -> float:
        if callable(data):
            return float(data(key))
        x = data
        for part in _parts(key):
            x = x[int(part)] if isinstance(x, list) else x[part]
        return float(x)
    getters = {source: value}
    if os.environ.get("PIXELKIT_DOCS_REWRITE"):
        update(None, pages, getters=getters)
    bad, _ = check(None, pages, getters=getters)
    return [f"{b['page']}:{b['line']}: {b['key']}: quoted {b['quoted']}, now {b.get('now') or b.get('why')}" for b in bad]


SCALE = re.compile(r"\*(" + NUMBER + r")$")


def _value(getters, src: str, key: str) -> float:
    """The current value of ``SRC:KEY`` (``KEY*SCALE``: times SCALE)."""
    m = SCALE.search(key) if src != "calc" else None      # a calc scales in its own arithmetic
    return getters[src](key[:m.start()] if m else key) * (float(m[1]) if m else 1.0)


def _elsewhere(m, getters) -> bool:
    """A mark (or a calc over a mark) of a source another test checks, absent from ``getters``."""
    srcs = [r[0] for r in REF.findall(m["key"])] if m["src"] == "calc" else [m["src"]]
    return any(s not in getters and (s in OTHER_SOURCES or s in SOURCES) for s in srcs)


def _sub_outside_code(line: str, fix) -> str:
    out, last = [], 0
    for m in _outside_code(line):
        out += [line[last:m.start()], fix(m)]
        last = m.end()
    return "".join(out) + line[last:]


def update(report: Path, files=None, getters=None) -> int:
    """Rewrite every quoted figure from ``report`` (or ``getters``, as ``check``; same digits); how many changed."""
    getters = getters if getters is not None else {name: make(report) for name, make in SOURCES.items()}
    changed = 0
    for page in files or pages():
        text = page.read_text()
        here = _with_local(getters, text)

        def fix(m):
            nonlocal changed
            if m["src"] not in here or _elsewhere(m, getters):
                return m.group(0)
            try:
                value = _value(here, m["src"], m["key"])
            except Unchecked:
                return m.group(0)
            tol = abs(value) * float(m["tol"]) / 100 if m["tol"] else _digits(m["num"]) * (1 + 1e-9)
            if abs(float(m["num"]) - value) <= tol:
                return m.group(0)
            changed += 1
            return _printed(value, m["num"]) + m.group(0)[len(m["num"]):]
        new = "\n".join(_sub_outside_code(line, fix) for line in text.split("\n"))
        if new != text:
            page.write_text(new)
    return changed


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    rep = Path(args[0]) if args else None          # no report: the marks that need no run only
    got = None if rep else {}
    if "--update" in sys.argv[1:]:
        print(f"{update(rep, getters=got)} quoted figure(s) rewritten")
    else:
        found, count = check(rep, getters=got)
        for b in found:
            print(f"{b['page']}:{b['line']}: {b['key']}: quoted {b['quoted']}, now {b.get('now') or b.get('why')}")
        print(f"{count} quoted figure(s), {len(found)} stale")
        sys.exit(1 if found else 0)
