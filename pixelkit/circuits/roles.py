"""A pixel as the role benches see it: a subcircuit whose ports play named roles.

Every pixel the role benches (``circuits.cds``), their measurements (``rolepix``) and ``verify``
run - the kit's 4T generator (``circuits.pixel4t``) or a designer's own netlist
(``spice.netlist_in`` read through ``families.netlist``) - is handed over as a
:class:`PixelCell`: the subcircuit, which of its ports is which role, which internal nodes are
worth saving (FD, the photodiode), and the light port the kit added. The benches drive roles,
never port names, so one bench serves every pixel.

Roles (``ROLES``): what each port is for and how a bench drives it.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..errors import ConfigError

#: role -> what it is (the design file's [netlist.ports] keys; docs/pixel-netlist.md)
ROLES = {
    "vdd": "pixel supply (the source follower's drain)",
    "col": "column line (the source follower's output through row select)",
    "rs": "row-select gate",
    "rst": "reset gate (FD reset)",
    "tg": "transfer gate (photodiode to FD)",
    "vrst": "reset drain (the FD reset level; absent: the reset drain is the supply port)",
    "sg": "storage gate (a storage node between the photodiode and FD)",
}
#: probe roles: internal nodes a measurement reads (saved, never driven)
PROBES = {"fd": "floating diffusion (the source follower's gate)",
          "pd": "photodiode node(s): its potential or its charge node"}
#: the roles every true-CDS rolling-shutter read needs
CDS_ROLES = ("vdd", "col", "rs", "rst", "tg")


@dataclass(frozen=True)
class PixelCell:
    """One pixel kind: ``subckt`` (with the light port ``light`` last), ``roles`` ((role, port), ...),
    ``probes`` ((role, internal node), ...), fixed ``bias`` voltages on other ports ((port, V), ...),
    the subcircuits and model cards it needs besides its own, and where it came from."""
    subckt: object
    roles: tuple
    probes: tuple = ()
    bias: tuple = ()
    support: tuple = ()
    source: str = "generator"
    light: str = "pklight"
    #: ((element name, "gate" | "drain"), ...): the devices whose noise the transient-noise check
    #: injects (``rolepix.trnoise``); empty: the check does not run on this cell
    noise: tuple = ()
    #: deck-level ``.model`` cards the cell's subcircuits use (a designer's netlist's)
    models: tuple = ()

    def port(self, role: str) -> str | None:
        return dict(self.roles).get(role)

    def probe(self, role: str) -> str | None:
        return dict(self.probes).get(role)

    def require(self, roles, what: str, where: str = "netlist.ports") -> None:
        """Refuse (exit 2) a measurement that needs a role this pixel does not map."""
        have = dict(self.roles)
        for r in roles:
            if r not in have:
                raise ConfigError(self.source, f"{where}.{r}", None,
                                  f"a port for role '{r}' ({ROLES[r]}): {what} needs it")

    def connections(self, nets: dict, light: str) -> tuple:
        """The instance's node list: each port's net by its role (``nets``: role -> net), a bias
        port its own net ``b_<port>``, the light port ``light``."""
        by_port = {p: r for r, p in self.roles}
        biased = dict(self.bias)
        out = []
        for p in self.subckt.ports:
            if p == self.light:
                out.append(light)
            elif p in by_port:
                out.append(nets[by_port[p]])
            elif p in biased:
                out.append(f"b_{p}")
            else:   # the loader refuses a port with no role or bias; a generator never makes one
                raise ConfigError(self.source, "netlist.ports", p, "a role or a bias for every port")
        return tuple(out)
