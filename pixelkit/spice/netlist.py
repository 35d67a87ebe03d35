"""Netlists as data, and the one writer that turns them into ngspice text.

Everything that reaches a deck goes through the constructors here, which
validate it: names and nodes are identifiers, values are finite numbers or
references to subcircuit parameters. No user path reaches a deck: a model file
is named through a kit-made link in the run's scratch folder (``models/<file>``,
see :meth:`Netlist.model_links`). Finally the whole text is held to an
allowlist - printable ASCII and ``\n`` - so no character that any reader
(ngspice, PySpice, ``str.splitlines``) treats as a line break (``\r``, ``\v``,
``\f``, ``\x1c-\x1e``, ``\x85``, U+2028, U+2029) can start a second line such as
``.control`` / ``shell``.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from ..errors import ConfigError

_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,63}$")
#: A node, or a node inside a subcircuit instance (``xafe_col_p_0.vm``, kit-made hand-overs).
_NODE = re.compile(r"^[A-Za-z0-9_]{1,64}(?:\.[A-Za-z0-9_]{1,64}){0,3}$")
_DECK_BAD = re.compile(r"[^\x20-\x7e\n]")
_SAVE = re.compile(r"^(?:[vi]\()?[A-Za-z0-9_.#]{1,128}\)?$")


def _save(name: str) -> str:
    """A vector to save: ``node`` (saved as its voltage), ``v(x1.fd)`` or ``i(vdd)``."""
    if not isinstance(name, str) or not _SAVE.match(name):
        raise ConfigError("netlist", "save", name, "a node name, v(node) or i(source)")
    return name if "(" in name else f"v({name})"


def check_name(value, what: str = "name") -> str:
    if not isinstance(value, str) or not _NAME.match(value):
        raise ConfigError("netlist", what, value,
                          "a SPICE name: a letter, then letters, digits or '_' (at most 64)")
    return value


def check_node(value, what: str = "node") -> str:
    if not isinstance(value, str) or not _NODE.match(value):
        raise ConfigError("netlist", what, value, "a node name of letters, digits or '_' "
                          "(or instance.node inside a subcircuit)")
    return value


@dataclass(frozen=True)
class Param:
    """A reference to a subcircuit parameter, written ``{name}``."""
    name: str

    def __post_init__(self):
        check_name(self.name, "parameter reference")


def fmt(value, what: str = "value") -> str:
    """A number (or parameter reference) as SPICE text; refuses anything else."""
    if isinstance(value, Param):
        return "{" + value.name + "}"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError("netlist", what, value, "a number")
    if not math.isfinite(value):
        raise ConfigError("netlist", what, value, "a finite number")
    return f"{float(value):.12g}"


@dataclass(frozen=True)
class Pulse:
    v1: float
    v2: float
    delay: float
    rise: float
    fall: float
    width: float
    period: float

    def text(self) -> str:
        vals = (self.v1, self.v2, self.delay, self.rise, self.fall, self.width, self.period)
        return "PULSE(" + " ".join(fmt(v, "pulse") for v in vals) + ")"


@dataclass(frozen=True)
class Pwl:
    points: tuple  # ((t, v), ...)

    def text(self) -> str:
        times = [t for t, _ in self.points]
        if any(b <= a for a, b in zip(times, times[1:])):
            raise ConfigError("netlist", "pwl", times, "strictly increasing times")
        return "PWL(" + " ".join(f"{fmt(t, 'pwl')} {fmt(v, 'pwl')}" for t, v in self.points) + ")"


#: The functions a behavioural expression may call (ngspice B-source functions; nothing else).
EXPR_FUNCTIONS = frozenset({"exp", "ln", "log", "sqrt", "abs", "min", "max", "pow", "tanh", "atan", "sin", "cos",
                            "u", "uramp", "v", "i"})
_EXPR_CHARS = re.compile(r"^[A-Za-z0-9_.+\-*/(),^ <>=!&|?:]{1,2000}$")
_EXPR_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_.#]*")


def check_expression(expr, what: str = "expression") -> str:
    """A behavioural expression: numbers, operators, node voltages ``V(node)`` / ``V(a,b)``, currents
    ``I(source)`` and the functions of ``EXPR_FUNCTIONS``; one line, no quote, brace or ';'."""
    if not isinstance(expr, str) or not _EXPR_CHARS.match(expr):
        raise ConfigError("netlist", what, expr, "an expression of numbers, operators, V(node), I(source) and "
                          "functions on one line (at most 2000 characters)")
    depth = 0
    for ch in expr:
        depth += {"(": 1, ")": -1}.get(ch, 0)
        if depth < 0:
            break
    if depth:
        raise ConfigError("netlist", what, expr, "an expression with balanced parentheses")
    rest = re.sub(r"\b[vViI]\s*\(\s*[A-Za-z0-9_.#]+\s*(,\s*[A-Za-z0-9_.#]+\s*)?\)", "0", expr)
    rest = re.sub(r"(?<![A-Za-z_])\d+\.?\d*(?:[eE][-+]?\d+)?[A-Za-z]*|(?<![A-Za-z_])\.\d+(?:[eE][-+]?\d+)?[A-Za-z]*",
                  "0", rest)
    for word in _EXPR_WORD.findall(rest):
        if word.lower() not in EXPR_FUNCTIONS:
            raise ConfigError("netlist", what, word, "a function of " + ", ".join(sorted(EXPR_FUNCTIONS - {"v", "i"}))
                              + ", V(node) or I(source)")
    return expr


@dataclass(frozen=True)
class Behavioral:
    """A behavioural source's value, ``I = expr`` or ``V = expr`` (an ngspice B element)."""
    kind: str          # "I" or "V"
    expr: str

    def __post_init__(self):
        if self.kind not in ("I", "V"):
            raise ConfigError("netlist", "behavioural source", self.kind, "I or V")
        check_expression(self.expr)

    def text(self) -> str:
        return f"{self.kind} = {self.expr}"


@dataclass(frozen=True)
class Trnoise:
    """A voltage source's transient noise: ``DC dc TRNOISE(na nt nalpha namp)`` (ngspice 4.1.7):
    white noise of rms ``na`` drawn every ``nt`` (linearly interpolated), plus 1/f^nalpha noise of
    amplitude ``namp``; the draws follow ``.options seed``."""
    dc: float
    na: float
    nt: float
    nalpha: float = 0.0
    namp: float = 0.0

    def text(self) -> str:
        return (f"DC {fmt(self.dc, 'trnoise')} TRNOISE({fmt(self.na, 'trnoise')} {fmt(self.nt, 'trnoise')} "
                f"{fmt(self.nalpha, 'trnoise')} {fmt(self.namp, 'trnoise')})")


@dataclass(frozen=True)
class Element:
    """One device line: ``name nodes... [value|model] [key=value ...]``."""
    name: str
    nodes: tuple
    value: object = None          # number, Param, Pulse, Pwl, Behavioral, Trnoise, or model/subckt name (str)
    params: tuple = ()            # ((key, number|Param), ...)

    def __post_init__(self):
        check_name(self.name, "element name")
        for n in self.nodes:
            check_node(n, f"node of {self.name}")
        if isinstance(self.value, str):
            check_name(self.value, f"model of {self.name}")
        for k, _v in self.params:
            check_name(k, f"parameter of {self.name}")

    def text(self) -> str:
        parts = [self.name, *self.nodes]
        v = self.value
        if isinstance(v, (Pulse, Pwl, Behavioral, Trnoise)):
            parts.append(v.text())
        elif isinstance(v, str):
            parts.append(v)
        elif v is not None:
            parts.append(fmt(v, self.name))
        parts += [f"{k}={fmt(x, f'{self.name}.{k}')}" for k, x in self.params]
        return " ".join(parts)


@dataclass(frozen=True)
class Model:
    """A ``.model name type (k=v ...)`` card written by the kit."""
    name: str
    kind: str
    params: tuple

    def __post_init__(self):
        check_name(self.name, "model name")
        check_name(self.kind, "model type")

    def text(self) -> str:
        body = " ".join(f"{check_name(k, 'model parameter')}={fmt(v, k)}" for k, v in self.params)
        return f".model {self.name} {self.kind} ({body})"


@dataclass(frozen=True)
class Subckt:
    name: str
    ports: tuple
    elements: tuple
    params: tuple = ()  # ((name, default), ...)
    models: tuple = ()  # ((model name, type, ((key, number), ...)), ...): local .model cards

    def __post_init__(self):
        check_name(self.name, "subcircuit name")
        for p in self.ports:
            check_node(p, f"port of {self.name}")

    def text(self) -> str:
        head = f".subckt {self.name} " + " ".join(self.ports)
        if self.params:
            head += " " + " ".join(f"{check_name(k)}={fmt(v, k)}" for k, v in self.params)
        cards = [f".model {check_name(m)} {check_name(kind)} ("
                 + " ".join(f"{check_name(k)}={fmt(v, k)}" for k, v in kv) + ")" for m, kind, kv in self.models]
        return "\n".join([head, *cards, *(e.text() for e in self.elements), f".ends {self.name}"])


@dataclass(frozen=True)
class Tran:
    step: float
    stop: float
    start: float = 0.0
    max_step: float | None = None
    uic: bool = False

    def text(self) -> str:
        s = f".tran {fmt(self.step)} {fmt(self.stop)} {fmt(self.start)}"
        if self.max_step is not None:
            s += f" {fmt(self.max_step)}"
        return s + (" uic" if self.uic else "")

    @property
    def kind(self) -> str:
        return "tran"


@dataclass(frozen=True)
class Op:
    def text(self) -> str:
        return ".op"

    @property
    def kind(self) -> str:
        return "op"


_OPTION_WORD = re.compile(r"^[a-z]{1,16}$")


@dataclass(frozen=True)
class Netlist:
    """A complete deck: title, includes, models, subcircuits, elements, options, analysis."""
    title: str
    elements: tuple
    analysis: object
    subckts: tuple = ()
    models: tuple = ()
    includes: tuple = ()          # Include objects of the technology (quoted paths)
    options: tuple = ()           # ((key, number|word), ...)
    ic: tuple = ()                # ((node, volts), ...)
    temperature_C: float = 27.0
    saves: tuple = ()             # node names to save; empty = everything
    meta: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        check_name(self.title, "deck title")
        names = [e.name.lower() for e in self.elements]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ConfigError("netlist", "element name", sorted(dup)[0], "unique element names")

    def model_links(self) -> dict:
        """Link name -> model folder: the runner makes each link in the run's scratch folder."""
        links = {}
        for inc in self.includes:
            if inc.folder not in links.values():
                links["models" if not links else f"models{len(links) + 1}"] = inc.folder
        return links

    def text(self) -> str:
        out = [f"* {self.title}: generated by pixelkit"]
        link_of = {folder: name for name, folder in self.model_links().items()}
        out += [inc.line(link_of[inc.folder]) for inc in self.includes]
        out += [m.text() for m in self.models]
        out += [s.text() for s in self.subckts]
        out += [e.text() for e in self.elements]
        opts = []
        for k, v in self.options:
            check_name(k, "option")
            if isinstance(v, str):
                if not _OPTION_WORD.match(v):
                    raise ConfigError("netlist", f"option {k}", v, "a lower-case word")
                opts.append(f"{k}={v}")
            else:
                opts.append(f"{k}={fmt(v, k)}")
        if opts:
            out.append(".options " + " ".join(opts))
        out.append(f".temp {fmt(self.temperature_C, 'temperature')}")
        if self.ic:
            out.append(".ic " + " ".join(f"v({check_node(n)})={fmt(v, 'ic')}" for n, v in self.ic))
        if self.saves:
            out.append(".save " + " ".join(_save(n) for n in self.saves))
        out.append(self.analysis.text())
        out.append(".end")
        return deck_text("\n".join(out) + "\n")


def deck_text(text: str) -> str:
    """``text`` if every character is printable ASCII or ``\n``; else a ConfigError naming the line."""
    bad = _DECK_BAD.search(text)
    if bad:
        start = text.rfind("\n", 0, bad.start()) + 1
        raise ConfigError("netlist", "deck text", text[start:bad.start() + 1][-80:],
                          f"printable ASCII only (character U+{ord(bad.group()):04X} could start a "
                          "new deck line)")
    return text
