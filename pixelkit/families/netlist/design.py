"""Design file of a pixel given as a SPICE netlist (``family = "netlist"``), validated on load.

``[netlist]`` names the file (relative to the design file, read by ``spice.netlist_in``: no
``.control``, no include outside the design's folder) and the subcircuit, maps its ports to roles
(``[netlist.ports]``: ``circuits.roles.ROLES``) or to fixed voltages (``[netlist.bias.<port>]``),
names internal nodes worth saving (``[netlist.probes]``: ``fd``, ``pd``) and the devices the light
falls on (``[netlist.light.<device>]``: a diode, whose photocurrent runs from its cathode to its anode,
or a capacitor, from its first node to its second, e.g. a behavioural photodiode's storage node,
with the area that shares the light). Every check refuses with exit 2 naming the field: a port the
subcircuit lacks, a port with no role and no bias, a role a true-CDS read needs left unmapped, a
probe or light device the subcircuit lacks, a device the light cannot enter.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from ...errors import ConfigError
from ...schema import ident, named, qty, table, text
from ..roledesign import RoleDesign, load_role_design


def _port(doc: str):
    return text("", doc=doc)


@dataclass(frozen=True)
class Ports:
    """Which port of the subcircuit plays which role (a role left out: the port is not there)."""
    vdd: str = _port("the pixel supply (the source follower's drain)")
    col: str = _port("the column line")
    rs: str = _port("the row-select gate")
    rst: str = _port("the reset gate")
    tg: str = _port("the transfer gate")
    vrst: str = _port("the reset drain (absent: the reset drain is the supply port)")
    sg: str = _port("a storage gate (the kit's benches have no storage-gate sequence yet: refused)")


@dataclass(frozen=True)
class Bias:
    voltage: float = qty("V", gt=-40.0, lt=40.0, doc="the fixed voltage on that port")
    name: str = field(default="", metadata=dict(kind="skip"))


@dataclass(frozen=True)
class Probes:
    fd: str = text("", doc="the floating diffusion (the follower's gate): the read noise's operating point")
    pd: str = text("", doc="the photodiode's node (its potential or charge node): saved for the waveforms")


@dataclass(frozen=True)
class LightDevice:
    area: float = qty("m2", gt=0, plausible=(1e-14, 1e-6), doc="the area of the device's share of the light")
    name: str = field(default="", metadata=dict(kind="skip"))


@dataclass(frozen=True)
class NetlistRef:
    file: str = text(doc="the SPICE file, relative to the design file")
    subckt: str = ident(doc="the pixel's subcircuit in it")
    ports: Ports = table(Ports, doc="the roles of its ports")
    bias: tuple = named(Bias, doc="ports held at a fixed voltage: [netlist.bias.<port>] voltage = ...")
    probes: Probes = table(Probes, default=Probes, doc="internal nodes the measurements read")
    light: tuple = named(LightDevice, doc="the devices the light falls on: [netlist.light.<device>] area = ...")


@dataclass(frozen=True)
class NetlistDesign(RoleDesign):
    family: str = text(choices=("netlist",), doc="a pixel from the designer's SPICE netlist")
    netlist: NetlistRef | None = table(NetlistRef, None, doc="the netlist, its subcircuit and the roles of its ports "
                                                             "(required)")
    pixel_cell: object = field(default=None, metadata=dict(kind="skip"), compare=False, repr=False)

    def cell(self):
        return self.pixel_cell

    def reloaded(self, raw: dict):
        return load_netlist_design(self.source, raw)


def load_netlist_design(path: str | Path, raw: dict | None = None) -> NetlistDesign:
    d = load_role_design(NetlistDesign, path, _netlist_given, raw=raw)
    return replace(d, pixel_cell=build_cell(d))


def _netlist_given(d) -> None:
    if d.netlist is None:
        from ...errors import MISSING
        raise ConfigError(d.source, "netlist", MISSING, "a [netlist] table: file, subckt and [netlist.ports]")


def build_cell(design):
    """The designer's subcircuit as a role cell (module docstring), every check made."""
    from ...circuits.ppd import LIGHT_PORT, LIGHT_SCALE
    from ...circuits.roles import CDS_ROLES, PixelCell
    from ...spice.netlist import Element, Subckt
    from ...spice.netlist_in import nodes_of, read_netlist, used_subckts
    src, nl = design.source, design.netlist
    folder = Path(src).parent
    parsed = read_netlist(folder / nl.file, root=folder)
    sub = parsed.subckts.get(nl.subckt.lower())
    if sub is None:
        raise ConfigError(src, "netlist.subckt", nl.subckt, "a subcircuit of " + nl.file + ": "
                          + (", ".join(s.name for s in parsed.subckts.values()) or "(it defines none)"))
    lib = (design.tech.mos.nmos, design.tech.mos.pmos)
    support = used_subckts(parsed, sub.name, lib, src)
    _check_models(design, parsed, [sub, *support])
    ports = {p.lower(): p for p in sub.ports}
    roles = []
    for role in ("vdd", "col", "rs", "rst", "tg", "vrst", "sg"):
        port = getattr(nl.ports, role)
        if not port:
            continue
        if port.lower() not in ports:
            raise ConfigError(src, f"netlist.ports.{role}", port, f"a port of {sub.name}: {', '.join(sub.ports)}")
        roles.append((role, ports[port.lower()]))
    if any(r == "sg" for r, _ in roles):
        raise ConfigError(src, "netlist.ports.sg", nl.ports.sg, "no storage gate: the kit's benches read a pixel "
                          "with a rolling-shutter true-CDS sequence (RST, SHR, TG, SHS) and have none for one yet")
    have = dict(roles)
    for role in CDS_ROLES:
        if role not in have:
            raise ConfigError(src, f"netlist.ports.{role}", None, f"a port of {sub.name} for role '{role}': every "
                              "measurement of this family reads the pixel with true CDS, which drives it")
    bias = []
    for b in nl.bias:
        if b.name.lower() not in ports:
            raise ConfigError(src, f"netlist.bias.{b.name}", b.voltage, f"a port of {sub.name}: {', '.join(sub.ports)}")
        bias.append((ports[b.name.lower()], b.voltage))
    taken = {p.lower() for _r, p in roles} | {p.lower() for p, _v in bias}
    for p in sub.ports:
        if p.lower() not in taken:
            raise ConfigError(src, "netlist.ports", p, f"a role or a [netlist.bias.{p}] voltage for every port of "
                              f"{sub.name}")
    if LIGHT_PORT in ports:
        raise ConfigError(src, "netlist.subckt", nl.subckt, f"a subcircuit without a port named {LIGHT_PORT} (the "
                          "kit's light port)")
    nodes = nodes_of(sub)
    probes = []
    for role in ("fd", "pd"):
        node = getattr(nl.probes, role)
        if node and node.lower() not in nodes:
            raise ConfigError(src, f"netlist.probes.{role}", node, f"a node of {sub.name}")
        if node:
            probes.append((role, node))
    if not nl.light:
        raise ConfigError(src, "netlist.light", None, f"at least one device of {sub.name} the light falls on "
                          "([netlist.light.<device>] area = ...)")
    by_name = {e.name.lower(): e for e in sub.elements}
    total = sum(x.area for x in nl.light)
    light = []
    for x in nl.light:
        e = by_name.get(x.name.lower())
        if e is None:
            raise ConfigError(src, f"netlist.light.{x.name}", x.area, f"a device of {sub.name} itself (not inside an "
                              "instance): " + ", ".join(el.name for el in sub.elements if el.name[0].upper() in "DC"))
        if e.name[0].upper() not in "DC":
            raise ConfigError(src, f"netlist.light.{x.name}", e.name, "a diode (its photocurrent: cathode to anode) "
                              "or a capacitor (a behavioural photodiode's node: first node to second)")
        a, b = (e.nodes[1], e.nodes[0]) if e.name[0].upper() == "D" else (e.nodes[0], e.nodes[1])
        light.append(Element(f"Gpk_{e.name}"[:64], (a, b, LIGHT_PORT, "0"), LIGHT_SCALE * x.area / total))
    cell_sub = Subckt(sub.name, (*sub.ports, LIGHT_PORT), (*sub.elements, *light), sub.params)
    return PixelCell(cell_sub, tuple(roles), tuple(probes), tuple(bias), tuple(support), source=src,
                     models=tuple(parsed.models.values()))


def _check_models(design, parsed, subs) -> None:
    """Every diode and MOSFET model a subcircuit names is the netlist's or the technology's."""
    t = design.tech
    known = {m.lower() for m in parsed.models} | {x.lower() for x in (t.mos.nmos, t.mos.pmos, t.photodiode.spice_model,
                                                                      t.photodiode.foundry_card or "") if x}
    for s in subs:
        for e in s.elements:
            if e.name[0].upper() in "DM" and e.value.lower() not in known:
                raise ConfigError(design.source, f"{s.name}.{e.name}", e.value, "a model of the netlist or of the "
                                  f"technology: {', '.join(sorted(known))}")
