"""A designer's SPICE netlist of a layout cell, read for LVS and extraction (``pixelkit signoff``).

Read with a bound (``readfile``) and parsed here, never by a SPICE program or KLayout's reader (which
follow ``.include`` and ``.lib``): only what describes the drawn devices is accepted -

- ``.subckt NAME pins`` / ``.ends``, ``.end``, ``.global``, comments (``*``, ``;``, ``$`` after a card)
  and ``+`` continuations;
- MOSFETs, as ``M`` cards or as ``X`` instances of the technology's MOS subcircuits (GF180's model
  library defines them as subcircuits; Xschem writes ``XM1 d g s b nfet_03v3 L=.. W=..``), W and L
  with SPICE suffixes (``0.6u``, ``6e-7``), ``m=`` multiplying W;
- diodes (``D a k model AREA= PJ=`` or ``A= P=``, m2 and m), MIM capacitors (``C a b model W= L=``, or
  ``c=`` the value), poly resistors (``R a b [bulk] model W= L=``);
- subcircuit instances (``X ... NAME``) of subcircuits of the file.

Anything else (``.include``, ``.lib``, ``.control``, ``.param``, sources, a model the technology's
extraction cannot produce, an unknown subcircuit) is refused with exit 2, naming the file, the line
and what is allowed. The result is the kit's LVS view (``schematic.lvs_view``'s dicts: the kit's LVS,
the foundry's and the extraction read it like the kit's own netlists), plus each element's original
card for the post-layout netlist.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from ...errors import ConfigError
from .schematic import VSS, pd_device

LIMIT = 64 << 20
_NUM = re.compile(r"^([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)(meg|mil|[tgkmunpfa])?[a-z]*$", re.I)
_SCALE = {"t": 1e12, "g": 1e9, "meg": 1e6, "k": 1e3, "m": 1e-3, "mil": 25.4e-6, "u": 1e-6, "n": 1e-9,
          "p": 1e-12, "f": 1e-15, "a": 1e-18, None: 1.0}
_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.#$<>\[\]:-]*$")
DOT_CARDS = (".subckt", ".ends", ".end", ".global")


def number(text: str) -> float | None:
    """A SPICE number with its scale suffix (``0.6u``, ``6e-7``, ``2MEG``); None when it is not one."""
    m = _NUM.match(text.strip())
    if not m:
        return None
    return float(m.group(1)) * _SCALE[m.group(2).lower() if m.group(2) else None]


@dataclass
class Card:
    name: str               # element name, prefix included (M1, XM1, D1 ...)
    nodes: list
    model: str
    params: str             # the card's parameter text, as written
    line: int


@dataclass
class Netlist:
    path: str
    circuits: dict = field(default_factory=dict)   # name -> {"pins": [...], "cards": [Card], "line": n}
    view: list = field(default_factory=list)       # schematic.lvs_view-style dicts, children first

    def top_view(self, top: str) -> list:
        """The view of circuit ``top`` and what it instantiates (children first)."""
        name = self.circuit_name(top)
        keep, order = set(), []

        def walk(n):
            if n in keep:
                return
            keep.add(n)
            for _i, target, _nets in next(c for c in self.view if c["name"] == n)["subs"]:
                walk(target)
            order.append(n)
        walk(name)
        by = {c["name"]: c for c in self.view}
        return [by[n] for n in order]

    def circuit_name(self, cell: str) -> str | None:
        """The circuit of the file that a layout cell draws (SPICE names are case-insensitive)."""
        return next((n for n in self.circuits if n.lower() == cell.lower()), None)


def _bad(path, line: int, found: str, allowed: str) -> ConfigError:
    return ConfigError(f"{path}:{line}", "netlist card", found[:80], allowed)


def _logical_lines(text: str, path) -> list:
    """(line number, card text) with continuations joined and comments removed."""
    out = []
    for k, raw in enumerate(text.splitlines(), 1):
        if "\x00" in raw:
            raise _bad(path, k, "a NUL byte", "a text SPICE netlist")
        s = raw.split(";", 1)[0].split(" $ ", 1)[0].rstrip()
        if not s.strip() or s.lstrip().startswith("*"):
            continue
        if s.lstrip().startswith("+"):
            if not out:
                raise _bad(path, k, s, "a '+' continuation after a card")
            out[-1] = (out[-1][0], out[-1][1] + " " + s.lstrip()[1:])
            continue
        out.append((k, s.strip()))
    return out


def _params(tokens: list, path, line: int) -> tuple[dict, list]:
    """{lower-case key: value text} of the ``key=value`` tokens, and the other tokens."""
    joined = " ".join(tokens)
    joined = re.sub(r"\s*=\s*", "=", joined)
    params, rest = {}, []
    for t in joined.split():
        if "=" in t:
            k, _, v = t.partition("=")
            if not k or not v:
                raise _bad(path, line, t, "parameters as name=value")
            params[k.lower()] = v
        else:
            rest.append(t)
    return params, rest


def read_netlist(path, tech) -> Netlist:
    """Read and check the netlist at ``path`` for technology ``tech``."""
    from ...readfile import read_text
    text = read_text(path, "netlist", "netlist", LIMIT)
    return parse(text, tech, str(path))


def _models(tech) -> dict:
    """{model name (lower case): kind} of the devices the technology's extraction produces."""
    out = {tech.mos.nmos.lower(): "mos", tech.mos.pmos.lower(): "mos", pd_device(tech).lower(): "diode",
           tech.photodiode.spice_model.lower(): "diode"}
    for old, new in tech.signoff.lvs_models:
        out[old.lower()] = out.get(new.lower(), "diode")
    if tech.passives is not None:
        out[tech.passives.mim_lvs.lower()] = "cap"
        out[tech.passives.mim_model.lower()] = "cap"
        out[tech.passives.res_model.lower()] = "res"
    return out


def _canonical(tech) -> dict:
    """{model name (lower case): the name the kit's LVS gives the device}."""
    out = {tech.mos.nmos.lower(): tech.mos.nmos, tech.mos.pmos.lower(): tech.mos.pmos,
           pd_device(tech).lower(): pd_device(tech), tech.photodiode.spice_model.lower(): pd_device(tech)}
    if tech.passives is not None:
        out[tech.passives.mim_lvs.lower()] = tech.passives.mim_lvs
        out[tech.passives.mim_model.lower()] = tech.passives.mim_lvs
        out[tech.passives.res_model.lower()] = tech.passives.res_model
    return out


def parse(text: str, tech, path: str = "netlist") -> Netlist:
    models, canon = _models(tech), _canonical(tech)
    known = ", ".join(sorted(set(canon.values())))
    nl = Netlist(path)
    cur = None
    lines = _logical_lines(text, path)
    for k, s in lines:
        tok = s.split()
        head = tok[0].lower()
        if head.startswith("."):
            if head not in DOT_CARDS:
                raise _bad(path, k, s, f"only {', '.join(DOT_CARDS)} dot cards, devices and subcircuit "
                           "instances (no .include / .lib / .control / .param: the netlist is read, never run)")
            if head == ".subckt":
                if cur is not None:
                    raise _bad(path, k, s, f".ends of subcircuit {cur} first (no nested subcircuits)")
                params, rest = _params(tok[1:], path, k)
                if not rest or not all(_NAME.match(x) for x in rest):
                    raise _bad(path, k, s, ".subckt NAME pin ... with names of letters, digits and _.#$<>[]:-")
                cur = rest[0]
                if cur.lower() in (c.lower() for c in nl.circuits):
                    raise _bad(path, k, s, f"one .subckt {cur} (it is defined twice)")
                nl.circuits[cur] = {"pins": rest[1:], "cards": [], "line": k}
            elif head == ".ends":
                if cur is None:
                    raise _bad(path, k, s, ".ends after a .subckt")
                cur = None
            elif head == ".end":
                break
            continue
        if cur is None:
            raise _bad(path, k, s, "devices inside a .subckt ... .ends (the cell the layout draws)")
        params, rest = _params(tok, path, k)
        if not all(_NAME.match(x) for x in rest):
            raise _bad(path, k, s, "node and model names of letters, digits and _.#$<>[]:-")
        kind = rest[0][0].upper()
        if kind not in "MXDCR" or len(rest) < 3:
            raise _bad(path, k, s, "an M, X, D, C or R card (sources and other elements are not drawn)")
        nl.circuits[cur]["cards"].append(Card(rest[0], rest[1:-1], rest[-1], " ".join(f"{a}={b}" for a, b in params.items()), k))
    if cur is not None:
        raise ConfigError(path, f".subckt {cur}", "(no .ends)", "every .subckt closed by .ends")
    if not nl.circuits:
        raise ConfigError(path, "netlist", "(no .subckt)", "a .subckt for the layout's top cell (and its sub-cells)")
    names = {n.lower(): n for n in nl.circuits}
    for name, c in nl.circuits.items():
        v = {"name": name, "pins": list(c["pins"]), "mos": [], "diodes": [], "caps": [], "res": [], "subs": []}
        for card in c["cards"]:
            params, _ = _params(card.params.split(), path, card.line)
            model = card.model.lower()
            kind = card.name[0].upper()
            if kind == "X" and model in names:
                v["subs"].append((card.name[1:], names[model], [_node(n) for n in card.nodes]))
                continue
            what = models.get(model)
            if what is None:
                raise ConfigError(f"{path}:{card.line}", f"device {card.name}", card.model,
                                  f"a device the extraction of technology {tech.name} produces ({known}) or a "
                                  "subcircuit of this file: the layout cannot have it")
            n = [_node(x) for x in card.nodes]
            val = lambda key, default=None: _value(params, key, default, path, card)   # noqa: E731
            if what == "mos":
                if len(n) != 4:
                    raise _bad(path, card.line, card.name, "a MOSFET with 4 nodes: drain gate source bulk")
                m = val("m", 1.0)
                v["mos"].append((card.name[1:], canon[model], *n, val("w") * m * 1e6, val("l") * 1e6))
            elif what == "diode":
                if len(n) != 2:
                    raise _bad(path, card.line, card.name, "a diode with 2 nodes: anode cathode")
                area = params.get("area", params.get("a"))
                perim = params.get("pj", params.get("p"))
                if area is None or perim is None:
                    raise _bad(path, card.line, card.name, "AREA= (m2) and PJ= (m) on the diode: LVS compares them")
                v["diodes"].append((card.name[1:], *n, canon[model], _num(area, path, card) * 1e12,
                                    _num(perim, path, card) * 1e6))
            elif what == "cap":
                if len(n) != 2:
                    raise _bad(path, card.line, card.name, "a capacitor with 2 nodes")
                w, l_ = val("w", 0.0), val("l", 0.0)
                c_val = params.get("c")
                cf = _num(c_val, path, card) if c_val else tech.passives.mim_value(w, l_)
                if cf <= 0:
                    raise _bad(path, card.line, card.name, "W= and L= of the top plate (m), or c= the value")
                v["caps"].append((card.name[1:], *n, canon[model], cf, w * 1e6, l_ * 1e6))
            else:
                if len(n) not in (2, 3):
                    raise _bad(path, card.line, card.name, "a resistor with 2 nodes (or 3: a bulk)")
                w, l_ = val("w"), val("l")
                v["res"].append((card.name[1:], n[0], n[1], canon[model], tech.passives.res_sheet * l_ / w,
                                 w * 1e6, l_ * 1e6))
        nl.view.append(v)
    nl.view = _children_first(nl.view, path)
    return nl


def _node(n: str) -> str:
    return VSS if n == "0" else n


def _num(text, path, card) -> float:
    x = number(text)
    if x is None or x != x or x in (float("inf"), float("-inf")):
        raise ConfigError(f"{path}:{card.line}", f"device {card.name}", text, "a SPICE number (0.6u, 6e-7)")
    return x


def _value(params, key, default, path, card) -> float:
    if key not in params:
        if default is None:
            raise ConfigError(f"{path}:{card.line}", f"device {card.name}", f"(no {key.upper()}=)",
                              f"{key.upper()}= on the card (LVS compares it)")
        return default
    x = _num(params[key], path, card)
    if x <= 0:
        raise ConfigError(f"{path}:{card.line}", f"device {card.name}", params[key], f"{key.upper()} > 0")
    return x


def _children_first(view: list, path) -> list:
    by = {c["name"]: c for c in view}
    order, state = [], {}

    def walk(n, chain):
        if state.get(n) == "done":
            return
        if state.get(n) == "open":
            raise ConfigError(path, f".subckt {n}", " -> ".join(chain + [n]), "subcircuits that do not instantiate "
                              "themselves")
        state[n] = "open"
        for _i, target, _nets in by[n]["subs"]:
            walk(target, chain + [n])
        state[n] = "done"
        order.append(by[n])
    for n in by:
        walk(n, [])
    return order


def post_layout_text(nl: Netlist, top: str, couplings: dict, title: str) -> str:
    """The designer's circuit ``top`` flattened (every card as written, its nodes and name prefixed by
    the instance path) with the extracted wiring capacitances between its nets: a subcircuit
    ``<top>_post`` with ``top``'s pins, for any SPICE run that includes the models the cards name.
    ``couplings``: {(net, net): F} with nets named as the extraction names them (``inst.net``)."""
    name = nl.circuit_name(top)
    c = nl.circuits[name]
    lines = [f"* {title}", f"* the designer's {Path(nl.path).name}, {name} flattened, with the wiring "
             "capacitances extracted from the layout (Cpex*)", f".subckt {name}_post " + " ".join(c["pins"])]

    def flat(n, prefix, m):
        if n in m:
            return m[n]
        return n if n in ("0", VSS) and not prefix else (prefix + n).replace(".", "_")

    def walk(circ, prefix, m):
        for card in nl.circuits[circ]["cards"]:
            target = nl.circuit_name(card.model) if card.name[0].upper() == "X" else None
            if target is not None:
                pins = nl.circuits[target]["pins"]
                walk(target, f"{prefix}{card.name[1:]}.", {p: flat(x, prefix, m) for p, x in zip(pins, card.nodes)})
                continue
            nodes = " ".join(flat(x, prefix, m) for x in card.nodes)
            lines.append(f"{card.name[0]}{(prefix + card.name[1:]).replace('.', '_')} {nodes} {card.model} {card.params}".rstrip())
    walk(name, "", {p: p for p in c["pins"]})
    for k, ((a, b), cf) in enumerate(sorted(couplings.items())):
        fa, fb = (x if x in ("0",) else x.replace(".", "_") for x in (a, b))
        lines.append(f"Cpex{k} {fa} {fb} {cf:.6e}")
    lines += [f".ends {name}_post", ""]
    return "\n".join(lines)
