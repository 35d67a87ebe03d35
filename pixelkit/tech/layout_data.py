"""The layout part of a technology file: layers by name, geometry rules by name, sign-off decks.

Generators never hold a process number (glayout's MappedPDK habit): they ask
``tech.layer("metal1")`` for a GDS layer and ``tech.rule("poly.extension.active")``
for a length, and the technology file answers. Three tables:

``[layers]``
    ``name = { layer = 34, datatype = 0 }``, or ``name = "other"`` (an alias: the
    light shield is drawn on the top metal, ``shield = "metal5"``). The names the
    generators use are listed in :data:`DRAWN`.
``[rules.<layer>]`` (sub-tables of ``[rules]``)
    ``width``, ``space``, ``area``, ``size`` (cuts), and pair rules in sub-tables
    ``[rules.<layer>.enclosure]`` / ``.extension`` / ``.space_to`` keyed by the other
    layer. A value is ``"0.22 um"`` or ``{ value = "0.22 um", rule = "DF.1a_3.3V" }``:
    the foundry rule it comes from, quoted in every error that names it.
``[signoff]``
    ``drc_deck`` (a deck the kit fetches, see ``layout.signoff.decks``, or a path
    relative to the technology file, pinned by ``drc_sha256``: a deck is code), ``drc_options``
    (the ``-rd name=value`` switches of the deck), ``lvs_deck`` (empty: the kit's own LVS; a
    path is pinned by ``lvs_sha256``).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

from ..errors import ConfigError
from ..schema import IDENT
from ..units import quantity

#: Every layer name a generator of the kit may ask for (a technology needs only those its
#: designs draw; a missing one is named when a generator asks).
DRAWN = ("nwell", "active", "poly", "nplus", "pplus", "contact", "metal1", "via1", "metal2", "via2",
         "metal3", "via3", "metal4", "via4", "metal5", "pd_marker", "mim_top", "mim_marker",
         "sab", "res_marker", "mim_l_marker", "shield", "opening", "boundary")
_PAIR_KINDS = ("enclosure", "extension", "space_to")
_SINGLE_KINDS = ("width", "space", "area", "size")
_SWITCH = re.compile(r"^[A-Za-z0-9_.+-]{1,64}$")


@dataclass(frozen=True)
class Layer:
    layer: int
    datatype: int

    def __str__(self) -> str:
        return f"{self.layer}/{self.datatype}"


@dataclass(frozen=True)
class Rule:
    """A length (m) or area (m2) and the foundry rule it comes from ("" when none is named)."""
    value: float
    name: str = ""

    def cite(self) -> str:
        return f" ({self.name})" if self.name else ""


@dataclass(frozen=True)
class Signoff:
    drc_deck: str = ""
    drc_sha256: str = ""
    drc_options: tuple = ()
    lvs_deck: str = ""
    lvs_options: tuple = ()
    base: str = ""          # folder of the technology file (relative deck paths)
    #: the foundry's physical-verification decks the kit fetches (LVS, density, antenna: signoff/foundry.py)
    pv_decks: str = ""
    pv_options: tuple = ()  # the foundry LVS deck's switches
    lvs_models: tuple = ()  # ((kit's device name, foundry's), ...) for the netlist the foundry LVS reads
    lvs_sha256: str = ""


@dataclass(frozen=True)
class LayoutData:
    layers: dict = field(default_factory=dict)      # name -> Layer
    aliases: dict = field(default_factory=dict)     # name -> name
    rules: dict = field(default_factory=dict)       # dotted key -> Rule
    signoff: Signoff = field(default_factory=Signoff)


def _layer(value, where, source) -> Layer:
    if not (isinstance(value, dict) and set(value) == {"layer", "datatype"}
            and all(isinstance(value[k], int) and not isinstance(value[k], bool) and 0 <= value[k] <= 65535
                    for k in value)):
        raise ConfigError(source, where, value, "{ layer = N, datatype = M } with whole numbers 0 - 65535, "
                          "or the name of another layer")
    return Layer(value["layer"], value["datatype"])


def parse_layers(raw, source: str) -> tuple[dict, dict]:
    if not isinstance(raw, dict) or not raw:
        raise ConfigError(source, "layers", raw, "a table of named layers")
    layers, aliases = {}, {}
    for name, value in raw.items():
        where = f"layers.{name}"
        if not IDENT.match(name):
            raise ConfigError(source, where, name, "a layer name of letters, digits and '_'")
        if isinstance(value, str):
            aliases[name] = value
        else:
            layers[name] = _layer(value, where, source)
    for name, target in aliases.items():
        if target not in layers:
            raise ConfigError(source, f"layers.{name}", target, f"the name of a layer of this table "
                              f"({', '.join(sorted(layers))})")
    seen = {}
    for name, lay in layers.items():  # two names on one GDS layer would merge their shapes
        if (lay.layer, lay.datatype) in seen:
            raise ConfigError(source, f"layers.{name}", str(lay),
                              f"a GDS layer of its own (layers.{seen[lay.layer, lay.datatype]} is {lay}); "
                              "write an alias (name = \"other\") to draw on the same layer (layout rule "
                              "distinct_layers)")
        seen[lay.layer, lay.datatype] = name
    return layers, aliases


def _rule_value(value, where, source, kind) -> Rule:
    name = ""
    if isinstance(value, dict):
        if set(value) - {"value", "rule"} or "value" not in value:
            raise ConfigError(source, where, value, '"0.22 um" or { value = "0.22 um", rule = "DF.1a_3.3V" }')
        name = value.get("rule", "")
        if not isinstance(name, str) or len(name) > 64 or not _SWITCH.match(name or "x"):
            raise ConfigError(source, f"{where}.rule", name, "a rule name of letters, digits and ._+-")
        value = value["value"]
    dim = "m2" if kind == "area" else "m"
    x = quantity(value, dim, where, source)
    # the range a real foundry rule has (issue 44: "0 um" or "1e-300 um" widths were drawn with):
    # widths, spaces, sizes 1 nm - 1 mm, areas 1e-6 um2 - 10000 um2; an enclosure, extension or
    # space to another layer may be exactly 0 (a flush edge), else at least 1 nm
    lo, hi, text = (1e-18, 1e-8, "from 1e-06 um2 to 10000 um2") if dim == "m2" else (1e-9, 1e-3, "from 1 nm to 1 mm")
    if not (lo <= x <= hi or (x == 0 and kind in _PAIR_KINDS)):
        raise ConfigError(source, where, value, f"a value {text}" + (" (or 0)" if kind in _PAIR_KINDS else "")
                          + " (the range a real design rule has)")
    return Rule(x, name)


def parse_rules(raw: dict, source: str) -> dict:
    """The dotted rule table from the sub-tables of ``[rules]``; ``raw`` is left with the rest."""
    out = {}
    for layer in [k for k, v in raw.items() if isinstance(v, dict)]:
        table = raw.pop(layer)
        for kind, value in table.items():
            where = f"rules.{layer}.{kind}"
            if kind in _PAIR_KINDS:
                if not isinstance(value, dict):
                    raise ConfigError(source, where, value, "a table keyed by the other layer")
                for other, v in value.items():
                    out[f"{layer}.{kind}.{other}"] = _rule_value(v, f"{where}.{other}", source, kind)
            elif kind in _SINGLE_KINDS:
                out[f"{layer}.{kind}"] = _rule_value(value, where, source, kind)
            else:
                raise ConfigError(source, where, value, f"one of {', '.join(_SINGLE_KINDS + _PAIR_KINDS)}")
    return out


def _switches(raw, where, source) -> tuple:
    if raw is None:
        return ()
    if not isinstance(raw, dict):
        raise ConfigError(source, where, raw, "a table of deck switches (name = \"value\")")
    for k, v in raw.items():  # these reach a command line: plain tokens only
        if not (isinstance(v, str) and _SWITCH.match(k) and _SWITCH.match(v)):
            raise ConfigError(source, f"{where}.{k}", v, "a plain value of letters, digits and ._+-")
    return tuple(sorted(raw.items()))


def parse_signoff(raw, source: str, base: str) -> Signoff:
    if raw is None:
        return Signoff(base=base)
    allowed = {"drc_deck", "drc_sha256", "drc_options", "lvs_deck", "lvs_sha256", "lvs_options", "pv_decks",
               "pv_options", "lvs_models"}
    if not isinstance(raw, dict) or set(raw) - allowed:
        bad = sorted(set(raw) - allowed)[0] if isinstance(raw, dict) else "signoff"
        raise ConfigError(source, f"signoff.{bad}", raw.get(bad) if isinstance(raw, dict) else raw,
                          f"one of {', '.join(sorted(allowed))}")
    for k in ("drc_deck", "drc_sha256", "lvs_deck", "lvs_sha256"):
        if not isinstance(raw.get(k, ""), str):
            raise ConfigError(source, f"signoff.{k}", raw[k], "a string")
    for k in ("drc_sha256", "lvs_sha256"):
        sha = raw.get(k, "")
        if sha and not re.fullmatch(r"[0-9a-f]{64}", sha):
            raise ConfigError(source, f"signoff.{k}", sha, "64 lower-case hex digits")
    for k in ("drc_deck", "lvs_deck"):   # a name or a path, never a line break or a control character
        v = raw.get(k, "")
        if v and (not v.isprintable() or len(v) > 4096):
            raise ConfigError(source, f"signoff.{k}", v, "a deck name or a file path of printable characters")
    pv = raw.get("pv_decks", "")
    if pv not in PV_DECKS:
        raise ConfigError(source, "signoff.pv_decks", pv, f"one of {', '.join(repr(x) for x in PV_DECKS)} (decks the "
                          "kit fetches and pins; empty: none)")
    return Signoff(raw.get("drc_deck", ""), raw.get("drc_sha256", ""),
                   _switches(raw.get("drc_options"), "signoff.drc_options", source),
                   raw.get("lvs_deck", ""), _switches(raw.get("lvs_options"), "signoff.lvs_options", source), base,
                   pv, _switches(raw.get("pv_options"), "signoff.pv_options", source),
                   _switches(raw.get("lvs_models"), "signoff.lvs_models", source), raw.get("lvs_sha256", ""))


#: foundry physical-verification deck sets the kit knows how to fetch and pin (signoff/fdpv.py)
PV_DECKS = ("", "gf180mcu_fd_pv")
