"""Design file of the 4T pinned-photodiode pixel (``designs/pixel4t_gf180.toml``), validated on load.

``[pixel]`` (pitch, PPD drawn size), ``[ppd]`` (the pinned photodiode's model parameters:
docs/pixel4t.md gives each one's source), ``[devices]`` (TG, RST, SF, RS), and the tables every
pixel read by role has (``families.roledesign``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ...errors import ConfigError
from ...schema import qty, table, text
from ..roledesign import RoleDesign, load_role_design
from .model import conversion_gain, tg_channel

_WL = (0.1e-6, 1e-3)


@dataclass(frozen=True)
class Pixel:
    pitch: float = qty("m", 8e-6, gt=0, plausible=(0.5e-6, 1e-3), doc="pixel cell side (square)")
    ppd_width: float = qty("m", 4e-6, gt=0, plausible=(0.1e-6, 1e-3), doc="drawn width of the pinned photodiode")
    ppd_height: float = qty("m", 4e-6, gt=0, plausible=(0.1e-6, 1e-3), doc="drawn height of the pinned photodiode")

    @property
    def area(self) -> float:
        return self.ppd_width * self.ppd_height

    @property
    def perimeter(self) -> float:
        return 2 * (self.ppd_width + self.ppd_height)

    def validate(self, path, source):
        for side in ("ppd_width", "ppd_height"):
            if getattr(self, side) > self.pitch:
                raise ConfigError(source, f"{path}.{side}", getattr(self, side), f"a PPD no larger than its cell "
                                  f"({self.pitch * 1e6:g} um)")


@dataclass(frozen=True)
class PpdParams:
    """The pinned photodiode's model (physics.ppd)."""
    v_pin: float = qty("V", 1.0, gt=0, plausible=(0.1, 3.0),
                       doc="pinning voltage: the potential of the empty, fully depleted PPD (at t_ref when v_bi is given)")
    v_bi: float | None = qty("V", None, gt=0, plausible=(0.3, 1.2),
                             doc="built-in potential of the PPD's junctions at t_ref: V_pin then follows it, "
                                 "V_pin(T) = v_pin - (V_bi(T) - v_bi), V_bi = U_T ln(N_A N_D / n_i^2) (about "
                                 "+1.3 mV/K at 0.9 V: the dark full well rises with temperature, as [Pelamatti2015] "
                                 "measured); absent: V_pin is one value at every temperature")
    c_area: float = qty("F/m2", 0.12e-3, gt=0, plausible=(1e-6, 1e-2),
                        doc="PPD capacitance per area (the dQ/dV of the filling well)")
    c_perimeter: float = qty("F/m", 0.05e-9, ge=0, plausible=(0.0, 1e-8), doc="PPD capacitance per perimeter")
    barrier: float = qty("V", 1.0, plausible=(-1.0, 3.0),
                         doc="TG-edge barrier: the transfer barrier is the TG channel's pinch-off potential minus this "
                             "(a pocket or barrier of the pinning implant under the TG edge)")
    j_gen: float = qty("A/m2", 1e-7, ge=0, plausible=(0.0, 1e-3),
                       doc="generation dark current per PPD area at t_ref (TG edge and isolation; ~n_i)")
    j_dif: float = qty("A/m2", 2e-8, gt=0, plausible=(1e-15, 1e-3),
                       doc="bulk diffusion dark current per PPD area at t_ref (~n_i^2): also the saturation current of "
                           "the PPD's diode, hence the full well's light dependence")
    t_ref: float = qty("K", 298.15, gt=0, plausible=(213.15, 473.15), doc="temperature of j_gen and j_dif")


@dataclass(frozen=True)
class Devices:
    tg_w: float = qty("m", 0.8e-6, gt=0, plausible=_WL, doc="transfer gate width (the PPD edge it spans)")
    tg_l: float = qty("m", 0.6e-6, gt=0, plausible=_WL, doc="transfer gate length")
    rst_w: float = qty("m", 0.6e-6, gt=0, plausible=_WL, doc="reset NMOS width")
    rst_l: float = qty("m", 0.5e-6, gt=0, plausible=_WL, doc="reset NMOS length")
    sf_w: float = qty("m", 1.0e-6, gt=0, plausible=_WL, doc="source-follower width")
    sf_l: float = qty("m", 0.5e-6, gt=0, plausible=_WL, doc="source-follower length")
    rs_w: float = qty("m", 0.6e-6, gt=0, plausible=_WL, doc="row-select width")
    rs_l: float = qty("m", 0.5e-6, gt=0, plausible=_WL, doc="row-select length")


@dataclass(frozen=True)
class Pixel4tDesign(RoleDesign):
    family: str = text(choices=("pixel4t",), doc="the 4T pinned-photodiode pixel with true CDS")
    pixel: Pixel = table(Pixel, default=Pixel, doc="cell pitch and the PPD's drawn size")
    ppd: PpdParams = table(PpdParams, default=PpdParams, doc="the pinned photodiode's model parameters")
    devices: Devices = table(Devices, default=Devices, doc="TG, RST, SF and RS sizes")
    #: the drawn cell's extraction (``layout.pixel4t.Extracted``) in the post-layout view; None: schematic
    post_layout: object = field(default=None, metadata=dict(kind="skip"))

    def cell(self):
        return cell_of(self)

    def reloaded(self, raw: dict):
        return load_pixel4t_design(self.source, raw)

    def fd_read(self, backend: str = "batch") -> dict:
        """FD at its read level by the closed form (``families.pixel4t.model.conversion_gain``: ``a_sf``,
        ``c_fd_F``, ...): what the role gap's kT/C term reads (``rolepix.gapnoise``)."""
        return conversion_gain(self, self.levels.v_rst_for(self.tech.supply) - 1.0, backend)

    def gate_area(self) -> float:
        """m2 of gate of the pixel's four transistors (TG, RST, SF, RS)."""
        d = self.devices
        return sum(getattr(d, f"{n}_w") * getattr(d, f"{n}_l") for n in ("tg", "rst", "sf", "rs"))


def load_pixel4t_design(path: str | Path, raw: dict | None = None) -> Pixel4tDesign:
    return load_role_design(Pixel4tDesign, path, raw=raw)


def cell_of(design):
    """The design's pixel as a role cell (``circuits.pixel4t``)."""
    from ...circuits.pixel4t import pixel4t
    return pixel4t(design, tg_channel(design))
