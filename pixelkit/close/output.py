"""What ``pixelkit close`` prints and writes: the iteration lines, the conflict, the summary,
``close.json`` and the revision's design file."""
from __future__ import annotations

import hashlib
import math
import re
from pathlib import Path

import numpy as np

#: A gradient counts as helping / hurting a spec above this (normalised margin per knob unit).
_SIGN = 1e-6


def _pct(x) -> str:
    return "-" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:+.3g} %"


def _behind(sc: dict) -> str:
    """A choice's screen: how far behind the best choice, and where."""
    if sc.get("behind_pct") is None:
        return "not measured"
    return ("the best on every row it fails" if sc["behind_pct"] == 0 else
            f"{-sc['behind_pct']:.3g} % behind the best at {sc['worst']}") + f", smallest margin {_pct(sc['short_pct'])}"


def _obj(value, objective) -> str:
    if value is None:
        return "-"
    from ..verify.figures import shown
    if objective.figure:
        f = objective.figures[objective.figure]
        return f"{shown(value, f.unit, f.dim):.5g} {f.unit}".strip()
    if objective.what == "area":
        return f"{value * 1e12:.5g} um2"
    return f"{value:.6g}"


def iteration_text(rec: dict, objective, label: str = "") -> str:
    head = (f"close{label}: iteration {rec['iteration']} ({rec['mode']}"
            + ("" if rec["mode"] == "start" else ", " + ("accepted" if rec["accepted"] else "rejected"))
            + f", verified on the {rec['verified_on']}"
            + (f", trust region {rec['radius']:.3g}" if rec["radius"] is not None else "") + "): "
            + ", ".join(f"{k} = {v}" for k, v in rec["knobs"].items())
            + f"; smallest margin {_pct(rec['smallest_margin_pct'])}; {objective.label()} "
            + _obj(rec["objective"], objective)
            + f"; SPICE {rec['spice_runs']} runs ({rec['spice_cached']} from cache), {rec['wall_s']:.0f} s")
    width = max((len(n) for n in rec["specs"]), default=0)
    lines = [head]
    for name, s in rec["specs"].items():
        lines.append(f"  {name.ljust(width)}  {_pct(s['margin_pct']):>10}  at {s['where'] or '-'}")
    return "\n".join(lines)


def conflicts(closer, p, last) -> dict:
    """The specs that conflict at the best compromise ``p``: the rows whose multipliers carry the
    max-min step of the last model (``close.step.restore`` at the tolerance's radius), and how each
    knob moves them."""
    from .knobs import at_bound
    from .step import restore
    st, model, radius = last
    u0 = closer.space.to_u(p.x)
    lo, hi = closer.space.u_bounds
    r = restore(model, u0, lo, hi, max(radius, closer.settings.tolerance), cap=0.0)
    if len(r.multipliers) < 2 and not r.bounds:   # one row against the trust region: the models over the box
        r = restore(model, u0, lo, hi, float(np.max(hi - lo)), cap=0.0)
    rows = sorted(r.multipliers.items(), key=lambda kv: -kv[1])
    index = {k: i for i, k in enumerate(model.keys)}
    specs = []
    for (name, c), lam in rows:
        m = p.margins.get((name, c))
        specs.append({"spec": name, "condition": c.label, "weight": lam,
                      "margin_pct": None if m is None else 100 * m})
    knobs = []
    for j, k in enumerate(closer.space.knobs):
        helps = [n for (n, c), _l in rows if model.g[index[(n, c)], j] > _SIGN]
        hurts = [n for (n, c), _l in rows if model.g[index[(n, c)], j] < -_SIGN]
        bound = {"min": k.lo, "max": k.hi}.get(at_bound(k, p.x[j]))
        knobs.append({"key": k.name, "raising_helps": helps, "raising_hurts": hurts,
                      "at_bound": at_bound(k, p.x[j]),
                      "bound": None if bound is None else closer.space.texts([bound], [k])[0]})
    names = [f"{s['spec']} at {s['condition']}" for s in specs]
    why = []
    for kn in knobs:
        if kn["raising_helps"] and kn["raising_hurts"]:
            why.append(f"raising {kn['key']} helps {', '.join(dict.fromkeys(kn['raising_helps']))} and hurts "
                       f"{', '.join(dict.fromkeys(kn['raising_hurts']))}")
        elif kn["at_bound"] and (kn["raising_helps"] or kn["raising_hurts"]):
            why.append(f"{kn['key']} is at its {kn['at_bound']} ({kn['bound']})")
    if len(specs) > 1:
        text = " against ".join(names)
    elif specs and any(k["at_bound"] for k in knobs):
        text = f"{names[0]} cannot reach its limit within the knobs' bounds"
    elif specs:
        text = f"{names[0]} cannot be raised further by the knobs (a local max-min point of the margins)"
    else:
        text = "no spec carries the last step (the models found no direction)"
    if why:
        text += ": " + "; ".join(why)
    floor = light_floor(p.design, specs, knobs)
    if floor:
        text += "; " + floor["text"]
    return {"specs": specs, "knobs": knobs, "text": text, "light_floor": floor}


def light_floor(design, specs, knobs) -> dict | None:
    """Under the collection model's light (``light.model = "modelled"``) a conflict on the secondary (a spec or a
    knob of it) is bounded by the secondary's effective opening, which no mask opening takes below the primary's
    light's part (``lightfigures.decomposition``: the carriers diffusing from under the primary and the light under
    the shield, the mask openings closed): that floor, the effective opening of the best compromise and its drawn
    opening (m2, and the sentence the conflict adds); None otherwise."""
    if design is None or design.light.model != "modelled":
        return None
    if not any("secondary" in s["spec"] for s in specs) and not any(k["key"].startswith("secondary.") for k in knobs):
        return None
    from ..layout.pex.lightfigures import decomposition
    d = decomposition(design)
    return {"floor_m2": d["primary_m2"], "effective_m2": d["total_m2"], "drawn_m2": d["drawn_m2"],
            "text": f"under the modelled light the secondary collects like an opening of {d['total_m2'] * 1e12:.3g} um2 "
                    f"(drawn {d['drawn_m2'] * 1e12:.3g} um2), of which {d['primary_m2'] * 1e12:.3g} um2 is the primary's "
                    "light whatever the mask opening: the effective opening's floor, which no knob of the opening "
                    "removes (docs/light-collection.md)"}


STATUS = {
    "closed": "closed: the revision passes every spec at every condition",
    "passing": "passing, stopped at max_iterations: the revision passes every spec at every condition; the "
               "objective may improve further",
    "infeasible": "no revision within the knobs' bounds passes: the smallest margin cannot be raised further",
    "not closed": "no passing revision found within max_iterations",
    "stalled": "no passing revision found: the trust region collapsed on candidates the linear models did not "
               "predict (a figure not smooth in the knobs), also when reopened; not a proof that none exists",
    "screened": "screened at its start, not closed: a combination ranked before it passed",
    "yield not met": "the revision passes every condition but its Monte Carlo yield does not reach min_yield",
    "not measured": "not every spec was measured at every condition of the closed revision",
}


def text(r: dict) -> str:
    lines = [f"close of {r['design']}: {STATUS.get(r['status'], r['status'])}",
             f"{candidates(r)} candidates, {r['spice_runs']} SPICE runs ({r['spice_cached']} from cache), "
             f"{r['wall_s']:.0f} s wall" + (f", {r['cpu_s']:.0f} s CPU" if r.get("cpu_s") is not None else "")
             + f"; objective {r['objective']['goal']}: {r['objective']['shown_start']} -> {r['objective']['shown']}"]
    for c in r.get("choices", []):
        sc = c.get("screen")
        lines.append(f"  with {c['choice']}: " + (f"screen (its start): {_behind(sc)}; " if sc else "")
                     + (STATUS['screened'].split(':')[0] if c['status'] == "screened" else
                        f"{STATUS.get(c['status'], c['status']).split(':')[0]}, smallest margin "
                        f"{_pct(c['smallest_margin_pct'])}, {r['objective']['goal']} {c['objective_shown']}")
                     + ("  <- chosen" if c["chosen"] else "") + (f"; conflict: {c['conflict']}" if c["conflict"] else ""))
    width = max(len(k["key"]) for k in r["knobs"])
    for k in r["knobs"]:
        if "min" not in k:
            lines.append(f"  {k['key'].ljust(width)}  {k['start']:>12} -> {k['value']:<12}"
                         + (f" of {', '.join(k['choices'])}" if k.get("choices") else ""))
            continue
        lines.append(f"  {k['key'].ljust(width)}  {k['start']:>12} -> {k['value']:<12} [{k['min']}, {k['max']}] "
                     f"{k['scale']}" + (f"  at its {k['at_bound']}" if k["at_bound"] else ""))
    lines.append("worst margin of each spec" + (" (the best compromise)" if not r["passes"] else "") + ":")
    width = max(len(n) for n in r["final"])
    for name, s in r["final"].items():
        lines.append(f"  {name.ljust(width)}  {_pct(s['margin_pct']):>10}  at {s['where'] or '-'}")
    if r.get("yield"):
        lines.append(r["yield"]["text"])
    if r.get("conflict"):
        lines.append("conflict: " + r["conflict"]["text"])
    if r.get("out"):
        lines.append(f"revision: {r['out']}")
    if r.get("json"):
        lines.append(f"path: {r['json']}")
    return "\n".join(lines)


def revision_name(out: Path, design) -> tuple[str, str]:
    """(name, revision) of the written revision: the file's stem when it is a valid name, and the
    next letter after a one-letter revision ("A" -> "B"), else ``<revision>-closed``."""
    from ..schema import IDENT
    name = out.stem if IDENT.match(out.stem) else f"{design.name}_closed"[:64]
    rev = design.revision
    nxt = chr(ord(rev) + 1) if len(rev) == 1 and rev.isalpha() and rev not in "Zz" else f"{rev}-closed"
    return name, nxt


def revision_text(design, overrides: dict, out: Path, record: dict) -> str:
    """The design file of the closed revision: the source file's text with the knobs' values, the name
    and the revision replaced in place (comments kept), checked to read back as intended; the
    source's technology / layout paths rewritten for ``out``'s folder. Falls back to the file
    re-written from its table when a key cannot be found in the text."""
    import tomllib

    from ..fileio import moved_path
    from ..readfile import read_text
    from ..schema import to_toml
    from ..tech import builtin_names
    name, rev = revision_name(out, design)
    edits = {"name": name, "revision": rev, **{k: v for k, v in overrides.items() if _changes(design, k, v)}}
    old_dir, new_dir = Path(design.source).parent, out.parent
    if design.raw["technology"] not in builtin_names():
        edits["technology"] = moved_path(design.raw["technology"], old_dir, new_dir)
    if isinstance(design.raw.get("layout"), dict) and "gds" in design.raw["layout"]:
        edits["layout.gds"] = moved_path(design.raw["layout"]["gds"], old_dir, new_dir)
    want = _with(design.raw, edits)
    source = read_text(Path(design.source), "design", "design")
    body = _edit(source, edits)
    if body is None or tomllib.loads(body) != want:
        body = to_toml(want)
    head = _header(design, record)
    return head + body


def _changes(design, key: str, value) -> bool:
    """Whether writing ``value`` at ``key`` changes the design (a value equal in SI keeps its text)."""
    from ..verify.close_table import field_of, value_of
    now = value_of(design, key)
    if value is None or now is None or isinstance(value, str) and isinstance(now, str):
        return value != now
    from ..units import quantity
    return quantity(value, field_of(type(design), key).metadata["dim"], key) != now


def candidates(record) -> int:
    return sum(1 for i in record["iterations"] if i["mode"] != "start")


def _header(design, record) -> str:
    src = "".join(c if c.isprintable() else "?" for c in str(design.source))
    moved = [f"{k['key']}" + "".join(f" (and {t})" for t in k.get("tied", ())) + f" {k['start']} -> {k['value']}"
             for k in record["knobs"] if k["start"] != k["value"]]
    lines = [f"# Closed by pixelkit close from {src} ({record['status']}, {candidates(record)} candidates, "
             f"objective {record['objective']['goal']}); the path: {Path(record['json']).name}",
             "# Knobs moved: " + ("; ".join(moved) or "none (the design passed as it was)")]
    return "\n".join(lines) + "\n"


def _with(raw: dict, edits: dict) -> dict:
    import copy
    out = copy.deepcopy(raw)
    for key, value in edits.items():
        cur = out
        *parts, last = key.split(".")
        for part in parts:
            cur = cur.setdefault(part, {})
        if value is None:
            cur.pop(last, None)
        else:
            cur[last] = value
    return out


_HEADER = re.compile(r"^\s*\[([^\[\]]+)\]\s*(#.*)?$")
_ASSIGN = re.compile(r'^(\s*)([A-Za-z0-9_"\.\- ]+?)(\s*=\s*)("(?:[^"\\]|\\.)*"|[^#\s][^#]*?)(\s*(#.*)?)$')


def _edit(source: str, edits: dict) -> str | None:
    """``source`` with each dotted key's value replaced where the file assigns it (a table header and a
    plain key), the line dropped for a value None, a key the file lacks written under its table's
    header; None when a key is assigned more than once or its table has no header of its own."""
    lines = source.splitlines(keepends=True)
    table, found, headers = "", {}, {"": -1}
    for i, line in enumerate(lines):
        h = _HEADER.match(line)
        if h:
            table = ".".join(p.strip().strip('"') for p in h.group(1).split("."))
            headers.setdefault(table, i)
            continue
        a = _ASSIGN.match(line.rstrip("\n"))
        if not a:
            continue
        key = ".".join(p.strip().strip('"') for p in a.group(2).split("."))
        full = f"{table}.{key}" if table else key
        if full in edits:
            if full in found:
                return None
            v = edits[full]
            nl = "\n" if line.endswith("\n") else ""
            lines[i] = "" if v is None else f"{a.group(1)}{a.group(2)}{a.group(3)}{_literal(v)}{a.group(5)}{nl}"
            found[full] = i
    for full, v in edits.items():
        if full in found or v is None:
            continue
        table, _, key = full.rpartition(".")
        if table not in headers or "." in key:
            return None
        at = headers[table]   # right after the header (top-level keys: at the top of the file)
        lines[at + 1:at + 1] = [f"{key} = {_literal(v)}\n"]
        headers = {t: (j + 1 if j > at else j) for t, j in headers.items()}
    return "".join(lines)


def _literal(v) -> str:
    from ..schema import _toml_string
    return _toml_string(v) if isinstance(v, str) else repr(v)


def digest(text_: str) -> str:
    return hashlib.sha256(text_.encode()).hexdigest()


def json_record(r: dict) -> dict:
    """close.json: everything but the design object; conditions as labels."""
    out = {k: v for k, v in r.items() if k not in ("design_obj",)}
    return out
