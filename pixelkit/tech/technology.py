"""A technology: supply, photodiode junction, MOS devices, model library, layout rules.

Technologies are TOML files. The built-in ones live in ``pixelkit/tech/builtin``;
a design names one of them or gives a path to its own file (which may point at a
model library the user holds, such as the real AMS C35 models under NDA).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import MISSING, ConfigError
from ..fileio import path_kind
from ..schema import flag, ident, load, named, num, qty, read_toml, table, text
from .layout_data import Layer, LayoutData, Rule, Signoff, parse_layers, parse_rules, parse_signoff
from .libcheck import check_devices
from .mimcorner import mim_factors
from .modellib import ModelLibrary, load_model_library
from .stack import Stack, parse_stack

BUILTIN_DIR = Path(__file__).parent / "builtin"
#: Plausibility ranges shared by several fields (SI): built-in potentials, temperatures.
_PB = (0.1, 2.0)
_TEMP = (213.15, 473.15)  # -60 .. 200 degC


@dataclass(frozen=True)
class Photodiode:
    """The photodiode junction (n-well / p-substrate) and its optical response."""
    cj: float = qty("F/m2", gt=0, plausible=(1e-6, 0.1), doc="bottom zero-bias capacitance")
    mj: float = num(gt=0, lt=1, plausible=(0.05, 0.95), doc="bottom grading coefficient")
    pb: float = qty("V", gt=0, plausible=_PB, doc="bottom built-in potential")
    cjsw: float = qty("F/m", ge=0, plausible=(0.0, 1e-8), doc="sidewall zero-bias capacitance")
    mjsw: float = num(gt=0, lt=1, plausible=(0.05, 0.95), doc="sidewall grading coefficient")
    pbsw: float = qty("V", gt=0, plausible=_PB, doc="sidewall built-in potential")
    reset_bias: float = qty("V", gt=0, plausible=(0.05, 40.0), doc="reverse bias at which the kit quotes C_jdep")
    dark_area: float = qty("A/m2", ge=0, plausible=(0.0, 1e-2), doc="dark current per area at t_ref")
    dark_perimeter: float = qty("A/m", ge=0, plausible=(0.0, 1e-6), doc="dark current per perimeter at t_ref")
    t_ref: float = qty("K", gt=0, plausible=_TEMP, doc="reference temperature of the dark current")
    spice_model: str = ident(doc="diode model name in netlists")
    builtin_model: bool = flag(doc="true: the kit writes the .model card from these fields")
    dark_doubling: float = qty("K", 7.0, gt=0, plausible=(1.0, 50.0),
                               doc="temperature step that doubles dark current (dark_law = doubling)")
    dark_law: str = text("doubling", choices=("doubling", "card"),
                         doc="doubling: dark_area/perimeter x 2^((T - t_ref)/dark_doubling); card: a foundry "
                             "card's thermal saturation terms with its own law (xti, eg, n), physics/dark.py")
    dark_xti: float = num(3.0, ge=0, plausible=(0.0, 10.0), doc="saturation-current temperature exponent (card law)")
    dark_eg: float = qty("V", 1.11, gt=0, plausible=(0.5, 2.0), doc="activation energy in eV (card law)")
    dark_n: float = num(1.0, gt=0, plausible=(0.5, 3.0), doc="emission coefficient (card law)")
    foundry_card: str = text("", doc="the foundry's diode card of this junction, measured and flagged by the kit "
                                     "when its reverse current is not a thermal one (techfit/pdcard.py)")
    qe_wavelength_nm: tuple = field(default=(), metadata=dict(kind="skip"))
    qe_value: tuple = field(default=(), metadata=dict(kind="skip"))


@dataclass(frozen=True)
class Mos:
    """MOS device names and the diffusion parasitics the analytic models need."""
    nmos: str = ident(doc="NMOS name in the model library (defined for every corner; checked when the file loads)")
    pmos: str = ident(doc="PMOS name in the model library")
    kind: str = text(choices=("subckt", "model"), doc="subckt: X instances; model: M instances")
    lmin: float = qty("m", gt=0, plausible=(1e-8, 1e-5), doc="minimum drawn gate length")
    wmin: float = qty("m", gt=0, plausible=(1e-8, 1e-5), doc="minimum drawn gate width")
    diff_ext: float = qty("m", gt=0, plausible=(1e-8, 1e-4), doc="source/drain diffusion length used for AD/AS/PD/PS")
    cj: float = qty("F/m2", ge=0, plausible=(0.0, 0.1), doc="n+ diffusion bottom junction capacitance")
    mj: float = num(gt=0, lt=1, plausible=(0.05, 0.95), doc="grading coefficient of cj (BSIM4 mjs)")
    pb: float = qty("V", gt=0, plausible=_PB, doc="built-in potential of cj (BSIM4 pbs)")
    cjsw: float = qty("F/m", ge=0, plausible=(0.0, 1e-8), doc="n+ diffusion field-sidewall capacitance per "
                      "perimeter (BSIM4 cjsws)")
    mjsw: float = num(gt=0, lt=1, plausible=(0.05, 0.95), doc="grading coefficient of cjsw (BSIM4 mjsws)")
    pbsw: float = qty("V", gt=0, plausible=_PB, doc="built-in potential of cjsw (BSIM4 pbsws)")
    cjswg: float = qty("F/m", ge=0, plausible=(0.0, 1e-8), doc="gate-edge sidewall (BSIM4 cjswgs)")
    mjswg: float = num(gt=0, lt=1, plausible=(0.05, 0.95), doc="grading coefficient of cjswg (BSIM4 mjswgs)")
    pbswg: float = qty("V", gt=0, plausible=_PB, doc="built-in potential of cjswg (BSIM4 pbswgs)")
    cgso: float = qty("F/m", ge=0, plausible=(0.0, 1e-8), doc="gate-source/drain overlap capacitance per width")
    cox: float = qty("F/m2", gt=0, plausible=(1e-4, 1.0), doc="gate oxide capacitance per area")
    vth_n: float = qty("V", gt=0, plausible=(0.05, 5.0), doc="nominal NMOS threshold (estimates only)")
    v_gate_max: float | None = qty("V", None, gt=0, plausible=(0.5, 40.0),
                                   doc="highest gate voltage the devices are rated for (a boosted gate rail, "
                                       "pixel.v_gate, may not exceed it); absent: the supply + 10 %")
    cgsl: float = qty("F/m", 0.0, ge=0, plausible=(0.0, 1e-8),
                      doc="bias-dependent (LDD) overlap per width (BSIM4 cgsl/cgdl, capmod 2)")
    ckappa: float = qty("V", 0.6, gt=0, plausible=(0.01, 10.0), doc="BSIM4 ckappas: LDD overlap voltage scale")
    js: float = qty("A/m2", 0.0, ge=0, plausible=(0.0, 1.0), doc="diffusion junction saturation current (BSIM4 jss)")
    jsw: float = qty("A/m", 0.0, ge=0, plausible=(0.0, 1e-6), doc="its field-sidewall part (BSIM4 jsws)")
    njs: float = num(1.0, gt=0.5, le=3, plausible=(0.8, 2.0), doc="junction emission coefficient (BSIM4 njs)")
    xtis: float = num(3.0, ge=0, le=10, plausible=(0.0, 6.0), doc="junction current temperature exponent (BSIM4 xtis)")
    t_nom: float = qty("K", 298.15, gt=0, lt=500, doc="temperature of js/jsw (the models' tnom)")
    kf_vg: float = qty("V2*F", 0.0, ge=0, plausible=(0.0, 1e-21),
                       doc="NMOS gate-referred 1/f noise S_vg = kf_vg / (cox W L f^ef), fitted to the model "
                           "library (circuits.noisebench.flicker_deck); 0 = no 1/f in the analytic chain")
    ef: float = num(1.0, gt=0, le=2, plausible=(0.5, 1.5), doc="1/f exponent of the NMOS (BSIM4 ef)")


@dataclass(frozen=True)
class LayoutRules:
    """Rules the layout generators and checks know (lengths in m)."""
    min_pd_side: float = qty("m", gt=0, plausible=(1e-7, 1e-3), doc="smallest photodiode side the generators draw")
    min_opening_side: float = qty("m", gt=0, plausible=(1e-8, 1e-3), doc="smallest side of a light-shield opening")
    opening_to_pd_edge: float = qty("m", ge=0, plausible=(0.0, 1e-4), doc="opening edge to PD edge, inside")
    pd_to_cell_edge: float = qty("m", ge=0, plausible=(0.0, 1e-4), doc="photodiode edge to the cell boundary (a PD "
                                 "wider than the pitch less twice this is refused)")
    shield_overlap: float = qty("m", ge=0, plausible=(0.0, 1e-4), doc="light shield beyond the photodiode edge; "
                                "read by no generator today (the shield is drawn by `[rules.shield]` and the openings)")
    grid: float = qty("m", gt=0, plausible=(1e-10, 1e-6), doc="manufacturing grid every drawn coordinate is on "
                      "(the mask opening is drawn to it)")


@dataclass(frozen=True)
class Mismatch:
    """Matching of what the model library does not vary itself. (The GF180MCU MOSFET
    models carry their own Pelgrom mismatch, switched on by ``sw_stat_mismatch``.)"""
    cap_pelgrom: float = qty("m", gt=0, plausible=(1e-10, 1e-6), doc="capacitor matching: sigma(dC/C) x sqrt(area); 1 %um = 1e-8 m")
    cap_density: float = qty("F/m2", gt=0, plausible=(1e-5, 0.1), doc="capacitance per area (gives a capacitor's area from its value)")
    mos_avt_n: float | None = qty("V*m", None, gt=0, plausible=(1e-10, 1e-7),
                                  doc="NMOS threshold matching A_VT (one device: sigma_VT = A_VT / sqrt(W L)), for "
                                      "the kit's Pelgrom draw when the model library has no mismatch statistics")
    mos_avt_p: float | None = qty("V*m", None, gt=0, plausible=(1e-10, 1e-7), doc="PMOS threshold matching A_VT")


@dataclass(frozen=True)
class Passives:
    """The capacitor and resistor the layout draws for a netlist's C and R (the readout's
    MIM capacitors, the op-amp's compensation resistor): their device names and the law
    that gives a drawn shape its value."""
    mim_model: str = ident(doc="MIM capacitor model of the model library (SPICE name)")
    mim_lvs: str = ident(doc="name the foundry LVS gives the drawn MIM capacitor (and the kit's netlists for LVS)")
    mim_c_area: float = qty("F/m2", gt=0, plausible=(1e-5, 0.1), doc="MIM capacitance per top-plate area")
    mim_c_perimeter: float = qty("F/m", ge=0, plausible=(0.0, 1e-8), doc="MIM capacitance per top-plate perimeter")
    res_model: str = ident(doc="poly resistor model (SPICE and LVS name)")
    res_sheet: float = qty("Ohm", gt=0, plausible=(1.0, 1e5), doc="sheet resistance of the resistor body (Ohm per square)")

    def mim_value(self, w: float, l: float) -> float:
        """Capacitance (F) of a w x l (m) top plate."""
        return self.mim_c_area * w * l + self.mim_c_perimeter * 2 * (w + l)


@dataclass(frozen=True)
class MetalPlane:
    """A metal level's height for the light field (``[collection.metals.<layer>]``)."""
    z: float = qty("m", gt=0, plausible=(1e-8, 1e-4), doc="bottom of the metal above the silicon surface")
    thickness: float = qty("m", gt=0, plausible=(1e-8, 1e-4), doc="metal thickness")
    name: str = field(default="", metadata=dict(kind="skip"))


@dataclass(frozen=True)
class Collection:
    """The silicon and the dielectric the light-collection model needs (docs/light-collection.md):
    minority-carrier transport, surface recombination, junction depths, the dielectric's index and,
    without a ``[stack]``, the metals' heights."""
    electron_diffusion_length: float = qty("m", gt=0, plausible=(1e-7, 1e-2),
                                           doc="electron (minority carrier) diffusion length in the p-substrate")
    electron_diffusivity: float = qty("m2/s", gt=0, plausible=(1e-5, 1e-2),
                                      doc="electron diffusivity in the p-substrate (kT/q x mobility)")
    hole_diffusion_length: float = qty("m", gt=0, plausible=(1e-8, 1e-2), doc="hole diffusion length in the n-wells")
    hole_diffusivity: float = qty("m2/s", gt=0, plausible=(1e-5, 1e-2), doc="hole diffusivity in the n-wells")
    surface_recombination: float = qty("m/s", gt=0, plausible=(1e-4, 1e5),
                                       doc="recombination velocity of the silicon surface under the oxide")
    substrate_thickness: float = qty("m", gt=0, plausible=(1e-6, 2e-3),
                                     doc="depth of the lightly doped silicon (an epitaxial layer, or the wafer)")
    well_depth: float = qty("m", gt=0, plausible=(1e-8, 1e-4), doc="n-well junction depth (photodiode and PMOS wells)")
    diffusion_depth: float = qty("m", gt=0, plausible=(1e-9, 1e-5), doc="N+ / P+ diffusion junction depth")
    substrate_bottom: str = text("recombining", choices=("recombining", "reflecting"),
                                 doc="what ends it: recombining (a wafer's back contact, a lifetime-killed substrate) "
                                     "or reflecting (a p+ substrate under a p- epitaxial layer)")
    dielectric_index: float = num(1.46, gt=1, plausible=(1.0, 4.0),
                                  doc="refractive index of the dielectric between the metals (SiO2: 1.46)")
    metals: tuple = named(MetalPlane, doc="heights of metal1 ... the top metal when the technology has no [stack] "
                                          "(with one, its conductors' heights are used)")


@dataclass(frozen=True)
class Technology:
    name: str = ident(doc="technology name, shown with every table and report (a built-in file's is the name designs use)")
    description: str = text(doc="one line saying what the process is and where its models come from")
    supply: float = qty("V", gt=0, le=40, plausible=(0.5, 40.0),
                        doc="the pixel's supply; a design's reset levels above it are refused")
    photodiode: Photodiode = table(Photodiode, doc="the photodiode junction, its dark current and QE")
    mos: Mos = table(Mos, doc="the MOS devices of the model library and their diffusion parasitics")
    rules: LayoutRules = table(LayoutRules, doc="the kit's own layout rules; the foundry's, per layer, in "
                               "[rules.<layer>] (docs/howto-new-technology.md)")
    mismatch: Mismatch | None = table(Mismatch, None, doc="matching the model library does not vary itself "
                                      "(Monte Carlo)")
    passives: Passives | None = table(Passives, None, doc="the MIM capacitor and poly resistor the readout is drawn "
                                      "with")
    collection: Collection | None = table(Collection, None, doc="the silicon and dielectric of the light-collection "
                                          "model (design key light.model = \"modelled\")")
    models: ModelLibrary = field(default=None, metadata=dict(kind="skip"))
    layout: LayoutData = field(default=None, metadata=dict(kind="skip"), repr=False)
    source: str = field(default="", metadata=dict(kind="skip"))
    stack: Stack | None = field(default=None, metadata=dict(kind="skip"), repr=False)
    #: process corner -> factor on the MIM capacitors (the library's MIM corner sections; tech/mimcorner.py)
    mim_corner: dict = field(default_factory=dict, metadata=dict(kind="skip"), repr=False)

    def layer(self, name: str) -> Layer:
        """The GDS layer the technology draws ``name`` on (aliases resolved)."""
        lay = self.layout.layers.get(self.layout.aliases.get(name, name))
        if lay is None:
            raise ConfigError(self.source, f"layers.{name}", MISSING,
                              f"a layer {name!r} in the technology's [layers] table (a generator draws on it)")
        return lay

    def rule(self, key: str) -> Rule:
        """The geometry rule ``key`` ("active.width", "poly.extension.active", ...)."""
        r = self.layout.rules.get(key)
        if r is None:
            layer, _, rest = key.partition(".")
            raise ConfigError(self.source, f"rules.{key}", MISSING,
                              f"a rule {rest!r} in the technology's [rules.{layer}] table (a generator needs it)")
        return r

    @property
    def signoff(self) -> Signoff:
        return self.layout.signoff

    def qe(self, wavelength_m):
        """Quantum efficiency at ``wavelength_m`` (linear interpolation of the table)."""
        import numpy as np
        if not self.photodiode.qe_wavelength_nm:
            raise ConfigError(self.source, "photodiode.qe_curve", None, "a QE table")
        return np.interp(np.asarray(wavelength_m) * 1e9, self.photodiode.qe_wavelength_nm,
                         self.photodiode.qe_value, left=0.0, right=0.0)


def builtin_names() -> list[str]:
    return sorted(p.stem for p in BUILTIN_DIR.glob("*.toml"))


#: wavelengths a QE table may cover (nm): deep UV to beyond silicon's band edge (~1100 nm)
QE_NM = (100.0, 2000.0)
QE_POINTS = 10000


def _qe_curve(raw, source):
    curve = raw.pop("qe_curve", None)
    if curve is None:
        raise ConfigError(source, "photodiode.qe_curve", None,
                          "a list of [wavelength_nm, qe] pairs")
    ok = isinstance(curve, list) and len(curve) >= 2 and all(
        isinstance(p, list) and len(p) == 2 and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                    for x in p) for p in curve)
    if not ok:
        raise ConfigError(source, "photodiode.qe_curve", curve,
                          "a list of at least two [wavelength_nm, qe] pairs of numbers")
    wl = [float(p[0]) for p in curve]
    qe = [float(p[1]) for p in curve]
    if not all(math.isfinite(x) for x in wl + qe):
        raise ConfigError(source, "photodiode.qe_curve", curve, "finite wavelengths (nm) and QE values")
    if any(b <= a for a, b in zip(wl, wl[1:])) or wl[0] <= 0:
        raise ConfigError(source, "photodiode.qe_curve", curve, "wavelengths > 0 in increasing order")
    if len(curve) > QE_POINTS:
        raise ConfigError(source, "photodiode.qe_curve", f"{len(curve)} points", f"at most {QE_POINTS} points")
    for i, x in enumerate(wl):   # issue 44: wavelengths x 1e300 were accepted
        if not QE_NM[0] <= x <= QE_NM[1]:
            raise ConfigError(source, f"photodiode.qe_curve[{i}]", curve[i],
                              f"a wavelength from {QE_NM[0]:g} to {QE_NM[1]:g} nm (where a silicon photodiode's "
                              "QE is measured) and a QE from 0 to 1")
    if any(not 0 <= q <= 1 for q in qe):
        raise ConfigError(source, "photodiode.qe_curve", curve, "QE values between 0 and 1")
    return tuple(wl), tuple(qe)


def load_technology(name_or_path: str | Path, relative_to: Path | None = None, source: str = "") -> Technology:
    """Load a built-in technology by name, or a technology TOML file by path.

    ``source``: the design file that names it (for error messages; default ``relative_to``).
    """
    text_ = str(name_or_path)
    source = source or str(relative_to or "")
    if text_ in builtin_names():
        path = BUILTIN_DIR / f"{text_}.toml"
    elif text_.endswith(".toml"):
        path = Path(text_)
        if not path.is_absolute() and relative_to is not None:
            path = relative_to / path
        if path_kind(path) is None:
            raise ConfigError(source, "technology", text_, f"an existing technology file (looked for {path})")
    else:
        raise ConfigError(source, "technology", text_,
                          f"a built-in technology ({', '.join(builtin_names())}) or a path to a .toml file")
    raw = read_toml(path, "technology")
    source = str(path)
    models_raw = raw.pop("models", None)
    pd_raw = raw.get("photodiode")
    qe = _qe_curve(pd_raw, source) if isinstance(pd_raw, dict) else ((), ())
    layers, aliases = parse_layers(raw.pop("layers", None), source)
    rules = parse_rules(raw["rules"], source) if isinstance(raw.get("rules"), dict) else {}
    signoff = parse_signoff(raw.pop("signoff", None), source, str(path.parent))
    stack = parse_stack(raw.pop("stack", None), source, set(layers) | set(aliases))
    tech = load(Technology, raw, "", source)
    models = load_model_library(models_raw, path.parent, source)
    pd = tech.photodiode
    object.__setattr__(pd, "qe_wavelength_nm", qe[0])
    object.__setattr__(pd, "qe_value", qe[1])
    object.__setattr__(tech, "models", models)
    object.__setattr__(tech, "layout", LayoutData(layers, aliases, rules, signoff))
    object.__setattr__(tech, "source", source)
    object.__setattr__(tech, "stack", stack)
    check_devices(tech, source)   # every device name resolves in every corner (tech/libcheck.py)
    object.__setattr__(tech, "mim_corner", mim_factors(tech, source))
    return tech
