"""Reading a designer's SPICE netlist (a file they wrote or Xschem exported) into the kit's netlist data.

The file is read like every input (``readfile``: a regular file, bounded: ``LIMIT`` bytes), and only a
subset of SPICE is accepted, each line parsed into the kit's validated ``Element`` / ``Subckt`` /
``Model`` objects - nothing of the file's text reaches a deck, the kit writes every line again
(``spice.netlist``'s writer and its printable-ASCII check). Accepted:

- ``.subckt NAME ports... [param=value ...]`` / ``.ends``; elements only inside a subcircuit;
- elements R, C, L (value, ``{param}``), D (model, area, pj), M / X (model or subcircuit, ``w= l= ...``),
  V / I with a DC value, E / G (linear controlled sources), F / H (current-controlled), B
  (``I = expr`` / ``V = expr``, functions of ``spice.netlist.EXPR_FUNCTIONS`` only);
- ``.model NAME d|nmos|pmos (numeric parameters)``;
- ``.param NAME = number`` (numbers only; ``{NAME}`` in an element is replaced by it);
- ``.include "file"``: a file inside the design's folder (resolved, no way out through ``..`` or a
  link), at most ``MAX_DEPTH`` deep, never one already open (an include loop);
- comments (``*`` lines, ``;`` and ``$`` tails), ``+`` continuation lines, ``.end``; Xschem's top-level
  ``**.subckt`` / ``**.ends`` (a schematic netlisted by Xschem 2.8 as it is) read as ``.subckt`` / ``.ends``.

Refused, exit 2 naming the file, line and what is allowed: ``.control`` / ``.endc`` (ngspice runs shell
commands there), every other dot card (``.lib``, ``.option``, ``.tran``, ``.save``, ``.temp``, ``.global``,
...: the kit owns the models, options and analyses), an unknown element letter, a time-varying source
inside a cell (the benches drive the pixel), a top-level element (export the pixel as a subcircuit), a
file beyond ``LIMIT`` or ``MAX_LINES``.
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import ConfigError
from .netlist import Behavioral, Element, Model, Subckt, check_expression, check_name

#: bytes of one netlist file (a pixel's netlist is a few kB; Xschem's with a whole readout a few hundred)
LIMIT = 4 << 20
#: logical lines over every file of one netlist
MAX_LINES = 100_000
#: include nesting
MAX_DEPTH = 8
#: element letter -> what it is
ELEMENTS = {"R": "resistor", "C": "capacitor", "L": "inductor", "D": "diode", "M": "MOSFET",
            "X": "subcircuit instance", "V": "DC voltage source", "I": "DC current source",
            "E": "VCVS", "G": "VCCS", "F": "CCCS", "H": "CCVS", "B": "behavioural source"}
MODEL_TYPES = ("d", "nmos", "pmos")
_SUFFIX = {"t": 1e12, "g": 1e9, "meg": 1e6, "k": 1e3, "m": 1e-3, "mil": 25.4e-6, "u": 1e-6, "n": 1e-9,
           "p": 1e-12, "f": 1e-15, "a": 1e-18}
_NUM = re.compile(r"^([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)([a-zA-Z]*)$")


@dataclass
class Parsed:
    """What a netlist file defines: subcircuits by name (lower case), model cards, parameters."""
    subckts: dict = field(default_factory=dict)
    models: dict = field(default_factory=dict)
    params: dict = field(default_factory=dict)
    files: list = field(default_factory=list)


def number(text: str, where: str, source: str, params: dict | None = None) -> float:
    """A SPICE number (``2.5f``, ``1meg``, ``10k``, ``1e-15``; a unit after the suffix ignored, ``1pF``), or
    ``{NAME}`` / ``NAME`` of a ``.param``."""
    t = text.strip()
    if t.startswith("{") and t.endswith("}"):
        t = t[1:-1].strip()
    if params and t.lower() in params:
        return params[t.lower()]
    m = _NUM.match(t)
    if not m:
        raise ConfigError(source, where, text, "a number (SI suffix allowed: f p n u m k meg g) or a .param name")
    x, suffix = float(m.group(1)), m.group(2).lower()
    for s in ("meg", "mil", "t", "g", "k", "m", "u", "n", "p", "f", "a"):
        if suffix.startswith(s):
            return x * _SUFFIX[s]
    return x


#: Xschem (2.8) netlists a schematic's top level as ``**.subckt NAME ports...`` ... ``**.ends``: read as the
#: subcircuit it is (``pixelkit netlist --schematic`` drawings netlisted by Xschem, tests/test_schematic.py)
XSCHEM_TOP = re.compile(r"^\*\*\.(subckt\s|ends\b)", re.I)


def _logical_lines(text: str, source: str):
    """(line number, text) of each logical line: comments dropped, '+' continuations joined."""
    out = []
    for no, raw in enumerate(text.splitlines(), 1):
        line = raw.rstrip()
        if XSCHEM_TOP.match(line):   # Xschem's top level: its .subckt / .ends written as comments
            line = line[2:]
        if not line.strip() or line.lstrip().startswith("*"):
            continue
        line = re.split(r"\s[;$]|^[;$]", line)[0].rstrip()
        if not line.strip():
            continue
        if line.lstrip().startswith("+"):
            if not out:
                raise ConfigError(source, f"line {no}", raw.strip()[:80], "a continuation after a line")
            out[-1] = (out[-1][0], out[-1][1] + " " + line.lstrip()[1:])
        else:
            out.append((no, line.strip()))
    return out


def _tokens(line: str) -> list[str]:
    """Split on blanks, keeping ``(...)``, ``{...}`` and ``k = v`` together."""
    line = re.sub(r"\s*=\s*", "=", line)
    out, depth, cur = [], 0, ""
    for ch in line:
        if ch in "({":
            depth += 1
        elif ch in ")}":
            depth -= 1
        if ch.isspace() and depth == 0:
            if cur:
                out.append(cur)
            cur = ""
        else:
            cur += ch
    if cur:
        out.append(cur)
    return out


def _include(path_text: str, here: Path, root: Path, source: str, where: str) -> Path:
    """The included file, resolved, refused unless inside ``root`` (the design's folder)."""
    name = path_text.strip().strip('"').strip("'")
    if not name or "\0" in name:
        raise ConfigError(source, where, path_text, "a file name")
    p = (here.parent / name)
    real = Path(os.path.realpath(p))
    root_real = Path(os.path.realpath(root))
    if root_real != real and root_real not in real.parents:
        raise ConfigError(source, where, name, f"a file inside the design's folder ({root}); the technology's "
                          "models are the kit's (leave model includes out)")
    return real


class _Reader:
    def __init__(self, root: Path):
        self.root, self.out, self.open, self.lines = root, Parsed(), [], 0

    def read(self, path: Path, depth: int = 0) -> None:
        from ..readfile import read_text
        real = Path(os.path.realpath(path))
        if real in self.open:
            raise ConfigError(str(path), ".include", str(path), "no include loop (the file is already being read: "
                              + " -> ".join(p.name for p in self.open) + ")")
        if depth > MAX_DEPTH:
            raise ConfigError(str(path), ".include", str(path), f"includes at most {MAX_DEPTH} deep")
        text = read_text(path, "netlist", "netlist", limit=LIMIT)
        self.open.append(real)
        self.out.files.append(str(real))
        source = str(path)
        cur: dict | None = None
        for no, line in _logical_lines(text, source):
            self.lines += 1
            if self.lines > MAX_LINES:
                raise ConfigError(source, f"line {no}", "...", f"a netlist of at most {MAX_LINES} lines")
            where = f"line {no}"
            head = line.split()[0].lower()
            if head.startswith("."):
                cur = self._card(head, line, cur, path, depth, source, where)
            elif cur is None:
                raise ConfigError(source, where, line[:80], "elements inside a .subckt (export the pixel as a "
                                  "subcircuit: the benches place it)")
            else:
                cur["elements"].append(self._element(line, source, where))
        if cur is not None:
            raise ConfigError(source, f".subckt {cur['name']}", "(no .ends)", "a .subckt closed by .ends")
        self.open.pop()

    def _card(self, head, line, cur, path, depth, source, where):
        tok = _tokens(line)
        if head in (".control", ".endc"):
            raise ConfigError(source, where, line[:80], "no .control block (ngspice runs shell commands in one): "
                              "the kit writes every analysis itself")
        if head == ".end":
            return cur
        if head == ".subckt":
            if cur is not None:
                raise ConfigError(source, where, line[:80], "a .subckt closed by .ends before the next")
            if len(tok) < 2:
                raise ConfigError(source, where, line[:80], ".subckt NAME ports...")
            name = check_name(tok[1], ".subckt name")
            ports, params = [], []
            for t in tok[2:]:
                if "=" in t:
                    k, v = t.split("=", 1)
                    params.append((check_name(k, "subcircuit parameter"), number(v, where, source, self.out.params)))
                elif t.lower() == "params:":
                    continue
                else:
                    ports.append(t)
            return {"name": name, "ports": ports, "params": params, "elements": [], "where": where}
        if head == ".ends":
            if cur is None:
                raise ConfigError(source, where, line[:80], ".ends after a .subckt")
            key = cur["name"].lower()
            if key in self.out.subckts:
                raise ConfigError(source, where, cur["name"], "one definition of each subcircuit")
            self.out.subckts[key] = Subckt(cur["name"], tuple(cur["ports"]), tuple(cur["elements"]),
                                           tuple(cur["params"]))
            return None
        if head == ".model":
            if len(tok) < 3:
                raise ConfigError(source, where, line[:80], ".model NAME TYPE (k=v ...)")
            name, rest = tok[1], " ".join(tok[2:])
            m = re.match(r"^([A-Za-z]+)\s*\(?(.*?)\)?$", rest)
            kind = m.group(1).lower() if m else ""
            if kind not in MODEL_TYPES:
                raise ConfigError(source, where, kind or rest[:40], f"a model of type {', '.join(MODEL_TYPES)}")
            kv = [t.split("=", 1) for t in _tokens(m.group(2))]
            if any(len(p) != 2 for p in kv):
                raise ConfigError(source, where, m.group(2)[:80], "model parameters as k=v")
            self.out.models[name.lower()] = Model(check_name(name, "model name"), kind,
                                                  tuple((check_name(k, "model parameter"), number(v, where, source))
                                                        for k, v in kv))
            return cur
        if head == ".param":
            for t in tok[1:]:
                if "=" not in t:
                    raise ConfigError(source, where, t, ".param NAME=number")
                k, v = t.split("=", 1)
                self.out.params[check_name(k, ".param name").lower()] = number(v, where, source)
            return cur
        if head in (".include", ".inc"):
            if len(tok) != 2:
                raise ConfigError(source, where, line[:80], ".include \"file\"")
            self.read(_include(tok[1], path, self.root, source, where), depth + 1)
            return cur
        raise ConfigError(source, where, head, "one of .subckt, .ends, .model, .param, .include, .end (the kit owns "
                          "the model library, the options and the analyses)")

    def _element(self, line, source, where) -> Element:
        tok = _tokens(line)
        name = tok[0]
        letter = name[0].upper()
        if letter not in ELEMENTS:
            raise ConfigError(source, where, name, "an element the kit reads: " + ", ".join(
                f"{k} ({v})" for k, v in ELEMENTS.items()))
        check_name(name, "element name")
        p = self.out.params

        def kv(items):
            out = []
            for t in items:
                if "=" not in t:
                    raise ConfigError(source, where, t, f"k=value parameters after the model of {name}")
                k, v = t.split("=", 1)
                out.append((check_name(k, f"parameter of {name}"), number(v, where, source, p)))
            return tuple(out)
        n_nodes = {"R": 2, "C": 2, "L": 2, "D": 2, "M": 4, "V": 2, "I": 2, "E": 4, "G": 4, "F": 2, "H": 2, "B": 2}
        if letter == "B":
            rest = line[len(name):].strip()
            m = re.match(r"^(\S+)\s+(\S+)\s+([IiVv])\s*=\s*(.+)$", rest)
            if not m:
                raise ConfigError(source, where, line[:80], "B n+ n- I=expr or V=expr")
            expr = m.group(4).strip()
            if expr.startswith("{") and expr.endswith("}"):
                expr = expr[1:-1]
            check_expression(expr, f"expression of {name}")
            return Element(name, (m.group(1), m.group(2)), Behavioral(m.group(3).upper(), expr))
        if letter == "X":
            pos = [t for t in tok[1:] if "=" not in t and t.lower() != "params:"]
            if len(pos) < 2:
                raise ConfigError(source, where, line[:80], "X nodes... SUBCKT [k=v ...]")
            return Element(name, tuple(pos[:-1]), check_name(pos[-1], f"subcircuit of {name}"),
                           kv([t for t in tok[1:] if "=" in t]))
        k = n_nodes[letter]
        if letter in "FH":
            if len(tok) < 5:
                raise ConfigError(source, where, line[:80], f"{letter} n+ n- VCONTROL gain")
            return Element(name, (tok[1], tok[2], check_name(tok[3], f"controlling source of {name}")),
                           number(tok[4], where, source, p))
        if len(tok) < k + 2 and letter != "M":
            raise ConfigError(source, where, line[:80], f"{ELEMENTS[letter]} with {k} nodes and a value")
        nodes, rest = tuple(tok[1:k + 1]), tok[k + 1:]
        if letter in "MD":
            if not rest:
                raise ConfigError(source, where, line[:80], f"a model after the nodes of {name}")
            return Element(name, nodes, check_name(rest[0], f"model of {name}"), kv(rest[1:]))
        if letter in "VI":
            vals = [t for t in rest if t.lower() != "dc"]
            if len(vals) != 1 or "(" in vals[0]:
                raise ConfigError(source, where, line[:80], f"a DC value only in {name} (the benches drive the "
                                  "pixel's time-varying inputs through its ports)")
            return Element(name, nodes, number(vals[0], where, source, p))
        vals = [t for t in rest if "=" not in t]
        if len(vals) != 1:
            raise ConfigError(source, where, line[:80], f"one value for {name}")
        return Element(name, nodes, number(vals[0], where, source, p), kv([t for t in rest if "=" in t]))


def read_netlist(path, root=None) -> Parsed:
    """Every subcircuit, model card and parameter of ``path`` and what it includes (module docstring);
    ``root``: the folder includes must stay in (default the file's own)."""
    path = Path(path)
    r = _Reader(Path(root) if root is not None else path.parent)
    r.read(path)
    return r.out


def used_subckts(parsed: Parsed, top: str, library: tuple, source: str) -> list:
    """The subcircuits ``top`` instantiates (depth first, each once), every instance checked: a
    subcircuit of the file or one the technology's model library provides (``library``)."""
    out, seen = [], set()

    def walk(name, chain):
        sub = parsed.subckts[name.lower()]
        for e in sub.elements:
            if e.name[0].upper() != "X":
                continue
            target = e.value.lower()
            if target in {x.lower() for x in library}:
                continue
            if target not in parsed.subckts:
                raise ConfigError(source, f"{sub.name}.{e.name}", e.value, "a subcircuit of the netlist or of the "
                                  f"technology's models ({', '.join(library)})")
            if target in chain:
                raise ConfigError(source, f"{sub.name}.{e.name}", e.value, "no subcircuit that contains itself")
            if target not in seen:
                seen.add(target)
                walk(target, chain | {target})
                out.append(parsed.subckts[target])
    walk(top, {top.lower()})
    return out


def nodes_of(sub) -> set:
    """Every node named inside subcircuit ``sub`` (its ports included), lower case."""
    out = {p.lower() for p in sub.ports}
    for e in sub.elements:
        nodes = e.nodes[:2] if e.name[0].upper() in "FH" else e.nodes
        out |= {n.lower() for n in nodes}
    return out
