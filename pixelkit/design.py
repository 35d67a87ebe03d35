"""Design files: the parameters of one chip revision, validated on load.

A design is a TOML file (``designs/dual_pixel_revA.toml``). Every dimensional
value carries a unit; the loaded :class:`Design` holds SI floats and its
technology. Sections: ``[primary]``, ``[secondary]`` (subpixel geometry, array,
timing), ``[pixel]`` (swing, SF bias, device sizes), ``[afe]``, ``[experiment]``
(the thesis's [Thesis2019] simulation experiment), and for sizing ``[optics]``, ``[scene]``,
``[sizing]``.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from .errors import MISSING, ConfigError
from .physics.conversion import photoactive_area, rectangle
from .readout_timing import Timing
from .schema import as_written, ident, integer, load, named, num, qty, read_toml, table, text
from .tech import Technology, load_technology
from .verify.close_table import CloseSettings, check as check_close
from .verify.spec import Spec, VerifySettings, check_conditions


@dataclass(frozen=True)
class Subpixel:
    pd_width: float = qty("m", gt=0, plausible=(0.1e-6, 1e-3),
                          doc="drawn width of the photodiode (n-well) junction; with pd_height it sets the junction "
                              "area and perimeter of C_jdep")
    pd_height: float = qty("m", gt=0, plausible=(0.1e-6, 1e-3), doc="drawn height of the photodiode junction")
    pitch: float = qty("m", gt=0, plausible=(0.2e-6, 2e-3),
                       doc="subpixel cell side (square cells); the PD must fit inside it")
    rows: int = integer(ge=1, le=100000, doc="rows of the array (frame simulations, row timing, the virtual camera)")
    cols: int = integer(ge=1, le=100000, doc="columns of the array (one column line, load and AFE each)")
    t_int: float = qty("s", gt=0, le=10.0, plausible=(1e-9, 10.0),
                       doc="integration (exposure) time of this array: EC opening to the end of the TG transfer")
    f_read: float = qty("Hz", gt=0, le=1e9, plausible=(1.0, 1e9),
                        doc="row readout rate: one row is read in 1 / f_read")
    mask_opening: float | None = qty("m2", None, gt=0, plausible=(1e-14, 1e-6),
                                     doc="metal-mask opening; absent = unmasked")
    timing: Timing = table(Timing, default=Timing, doc="global-shutter sequence and row read of this array")
    extracted: dict | None = field(default=None, metadata=dict(kind="skip"), compare=False)
    #: the collection model's figures (``light.model = "modelled"``): photoactive_area_m2 (the effective
    #: opening, lit like the primary), gse (eta_pd / eta_fd), over the scene's spectrum
    modelled: dict | None = field(default=None, metadata=dict(kind="skip"), compare=False)

    @property
    def area(self) -> float:
        """PD junction area: extracted from the layout when the design points at one, else drawn."""
        if self.extracted:
            return self.extracted["pd_area_m2"]
        return rectangle(self.pd_width, self.pd_height)[0]

    @property
    def perimeter(self) -> float:
        if self.extracted:
            return self.extracted["pd_perimeter_m"]
        return rectangle(self.pd_width, self.pd_height)[1]

    @property
    def photoactive_area(self) -> float:
        """The area that, lit like the primary, collects this subpixel's signal: the mask opening (or the
        PD) as drawn or extracted, or the collection model's effective opening (``modelled``)."""
        if self.modelled:
            return self.modelled["photoactive_area_m2"]
        if self.extracted:
            return self.extracted["photoactive_area_m2"]
        return photoactive_area(self.pd_width, self.pd_height, self.mask_opening)

    def validate(self, path, source, raw):
        for side in ("pd_width", "pd_height"):
            if getattr(self, side) > self.pitch:
                raise ConfigError(source, f"{path}.{side}", as_written(raw, side, getattr(self, side)),
                                  f"a PD no larger than its {as_written(raw, 'pitch', '')} cell "
                                  "(layout rule pd_to_cell_edge)")
        if self.mask_opening is not None and self.mask_opening > self.area:
            raise ConfigError(source, f"{path}.mask_opening", as_written(raw, "mask_opening", self.mask_opening),
                              f"an opening no larger than the PD area ({self.area * 1e12:g} um2)")


#: Plausible transistor width / length: 0.1 um to 1 mm.
_WL = (0.1e-6, 1e-3)


@dataclass(frozen=True)
class Devices:
    """Transistor sizes of the 5T pixel and its column (W, L in m); both arrays use the same sizes."""
    ec_w: float = qty("m", 0.6e-6, gt=0, plausible=_WL, doc="EC (exposure control) gate width: resets the PD")
    ec_l: float = qty("m", 0.5e-6, gt=0, plausible=_WL, doc="EC gate length")
    tg_w: float = qty("m", 0.6e-6, gt=0, plausible=_WL, doc="TG (transfer gate) width: PD to FD")
    tg_l: float = qty("m", 0.5e-6, gt=0, plausible=_WL, doc="TG length")
    rst_w: float = qty("m", 0.6e-6, gt=0, plausible=_WL, doc="RST (FD reset) width")
    rst_l: float = qty("m", 0.5e-6, gt=0, plausible=_WL, doc="RST length")
    sf_w: float = qty("m", 1.0e-6, gt=0, plausible=_WL, doc="source-follower width (its gate is FD)")
    sf_l: float = qty("m", 0.5e-6, gt=0, plausible=_WL, doc="source-follower length")
    rs_w: float = qty("m", 0.6e-6, gt=0, plausible=_WL, doc="RS (row select) width")
    rs_l: float = qty("m", 0.5e-6, gt=0, plausible=_WL, doc="RS length")
    sw_w: float = qty("m", 1.0e-6, gt=0, plausible=_WL, doc="S1X/S2X column sampling switches: width")
    sw_l: float = qty("m", 0.35e-6, gt=0, plausible=_WL, doc="S1X/S2X length")
    load_w: float = qty("m", 1.0e-6, gt=0, plausible=_WL, doc="column current-source load: width")
    load_l: float = qty("m", 2.0e-6, gt=0, plausible=_WL, doc="column current-source load: length")


@dataclass(frozen=True)
class Pixel:
    swing: float = qty("V", gt=0, plausible=(0.05, 5.0),
                       doc="pixel swing: the PD / FD voltage range of a full signal (1.5 V in [Thesis2019] table 3.2)")
    sf_bias: float = qty("A", gt=0, le=1e-3, plausible=(1e-9, 1e-3), doc="column current-source load of the SF")
    column_cap: float = qty("F", 200e-15, gt=0, plausible=(1e-16, 1e-8),
                            doc="column-line parasitic capacitance (a real column line has some: > 0)")
    v_pd_reset: float = qty("V", 2.0, gt=0, plausible=(0.1, 40.0),
                            doc="EC drain: PD reset level (hard reset below VDD - Vth)")
    v_fd_reset: float = qty("V", 2.0, gt=0, plausible=(0.1, 40.0), doc="RST drain: FD reset level")
    gate_drive: str = text("supply", choices=("supply", "boosted"),
                           doc="the circuit that drives the EC, TG and RST gates high: supply = the row drivers "
                               "run from the supply (the gates follow it, -10 % included: a 2.0 V reset turns soft "
                               "at slow corners); boosted = they run from a regulated rail at pixel.v_gate, the same "
                               "at every supply condition: the layout draws a level-shifting row driver per line on "
                               "the chip's pin vgate, compared by LVS (docs/pixel-model.md)")
    v_gate: float | None = qty("V", None, gt=0, plausible=(0.5, 40.0),
                               doc="the boosted rail (gate_drive = \"boosted\"): the EC, TG and RST gate-high level; "
                                   "at most the devices' rated gate voltage (technology mos.v_gate_max)")
    gse: float = num(1000.0, ge=1, le=1e9, plausible=(10.0, 1e7), doc="FD shielding: the storage node collects 1/gse of the PD's "
                     "photocurrent (charge ratio eta_pd / eta_FD)")
    devices: Devices = table(Devices, default=Devices, doc="transistor sizes of the pixel and its column")


@dataclass(frozen=True)
class Afe:
    c11: float = qty("F", gt=0, plausible=(1e-18, 1e-9), doc="input capacitor")
    c12: float = qty("F", gt=0, plausible=(1e-18, 1e-9), doc="offset-storage capacitor")
    c13: float = qty("F", gt=0, plausible=(1e-18, 1e-9), doc="feedback capacitor")
    vref: float = qty("V", gt=0, plausible=(0.05, 40.0),
                      doc="AFE reference: the output at zero signal, V_out = V_ref - (C11/C13)(V_rst - V_sig)")
    opamp: str = text("macro", choices=("macro", "ota"),
                      doc="macro: the Gm-R macromodel (gain, gbw, noise_r, noise_corner); ota: the transistor OTA")
    gain: float = num(1000.0, gt=1, plausible=(1.0, 1e7), unit_required=True,
                      doc="macromodel DC gain with its unit ('60 dB' or '1000 V/V')")
    gbw: float = qty("Hz", 50e6, gt=0, plausible=(1e3, 1e11), doc="macromodel gain-bandwidth")
    noise_r: float = qty("Ohm", 25e3, ge=0, plausible=(0.0, 1e8),
                         doc="macromodel input-referred thermal noise as an equivalent noise resistance: "
                             "e_n^2 = 4 k T R_n (25 kOhm = 20 nV/rtHz at 27 degC; 0 = noiseless)")
    noise_corner: float = qty("Hz", 100e3, ge=0, plausible=(0.0, 1e9),
                              doc="macromodel 1/f corner: input PSD e_n^2 (1 + f_c / f)")
    supply_current: float = qty("A", 10e-6, ge=0, plausible=(0.0, 1e-2),
                                doc="quiescent supply current of the macromodel op-amp (power only: the macromodel "
                                    "draws nothing itself; the OTA draws its own)")
    ota_bias: float = qty("A", 10e-6, gt=0, plausible=(1e-8, 1e-3),
                          doc="the transistor OTA's reference current (afe.opamp = \"ota\"): its mirrors give the "
                              "input pair's tail 2x and the output stage 4x, so the OTA draws 7x this from the "
                              "supply; the column's AFE power and the OTA's gm (GBW, settling) follow it")
    ota_cc: float = qty("F", 1e-12, gt=0, plausible=(1e-15, 1e-10),
                        doc="the OTA's Miller compensation capacitor: its GBW is the input pair's gm over it, "
                            "its slew rate the tail current (2 x ota_bias) over it")
    ota_rz: float = qty("Ohm", 5e3, ge=0, plausible=(0.0, 1e7),
                        doc="the OTA's nulling resistor in series with ota_cc (about 1 / gm of the output "
                            "stage moves the right-half-plane zero out)")
    nonoverlap: float = qty("s", 20e-9, gt=0, plausible=(1e-11, 1e-3), doc="non-overlap of the two clock phases")
    f_clk: float = qty("Hz", 500e3, gt=0, plausible=(1.0, 1e9),
                       doc="double-sampling rate (one signal + one reset per period)")


@dataclass(frozen=True)
class Experiment:
    """The same-window simulation experiment of [Thesis2019] (fig. A.1 - A.3)."""
    t_window: float = qty("s", 16e-6, gt=0, le=1e-3, plausible=(1e-8, 1e-3), doc="exposure window of the experiment")
    mid_fraction: float = num(0.5, gt=0, lt=1, plausible=(0.01, 0.99), doc="primary target: fraction of swing")
    low_fraction: float = num(0.05, gt=0, lt=1, plausible=(0.001, 0.99), doc="secondary target: fraction of swing")


@dataclass(frozen=True)
class Optics:
    focal_length: float = qty("m", gt=0, le=1.0, plausible=(1e-4, 1.0),
                              doc="lens focal length (field of view and the image of the scene)")
    f_number: float = num(gt=0.5, le=64, doc="lens f-number N: sensor irradiance ~ scene radiance / (4 N^2)")
    transmission: float = num(0.9, gt=0, le=1, plausible=(0.01, 1.0), doc="lens transmission (fraction of light through)")


@dataclass(frozen=True)
class Scene:
    """Measurement geometry ([Thesis2019] fig. 2.3) and light levels for sizing."""
    distance: float = qty("m", gt=0, plausible=(0.01, 1e5), doc="distance from the camera to the lane")
    speed_min: float = qty("m/s", gt=0, plausible=(0.01, 1000.0),
                           doc="slowest vehicle to measure: its trace must still be min_trace_px long")
    speed_max: float = qty("m/s", gt=0, plausible=(0.01, 1000.0),
                           doc="fastest vehicle: its trace must fit the field of view, the primary image stay sharp")
    background: float = qty("lx", gt=0, plausible=(1e-6, 2e5),
                            doc="scene illuminance at which the primary sits at mid-scale")
    headlight: float = qty("W/m2", gt=0, plausible=(1e-9, 1e5),
                           doc="headlight irradiance at the sensor (the spot's image)")
    reflectance: float = num(0.2, gt=0, le=1, plausible=(1e-3, 1.0),
                             doc="diffuse reflectance of the scene (background radiance from its illuminance)")
    spectrum_temperature: float = qty("K", 2856.0, gt=1000, plausible=(1000.0, 20000.0),
                                      doc="black-body colour temperature of the light")
    max_temperature: float = qty("K", 358.15, gt=0, lt=500, plausible=(213.15, 473.15), doc="maximum die temperature")

    def validate(self, path, source, raw):
        if self.speed_max < self.speed_min:
            raise ConfigError(source, f"{path}.speed_max", as_written(raw, "speed_max", self.speed_max),
                              f"a speed >= speed_min ({as_written(raw, 'speed_min', '')})")


@dataclass(frozen=True)
class Sizing:
    t_ratio: float | None = num(None, gt=0, plausible=(1e-3, 1e6), doc="fixed t_secondary / t_primary; absent = free")
    level: str = text("spice", choices=("analytic", "spice"),
                      doc="which model level's solution is the sized design: the PD node's C(V) or the SPICE curves")
    objective: str = text("trace", choices=("trace", "margin"), doc="trace: longest trace; margin: centre the bounds")
    min_trace_px: float = num(5.0, gt=0, plausible=(0.1, 1e5), doc="shortest usable trace at speed_min (speed accuracy)")
    fov_fraction: float = num(0.8, gt=0, le=1, plausible=(0.01, 1.0), doc="longest trace at speed_max, as a fraction of the width")
    max_motion_px: float = num(1.0, gt=0, plausible=(0.01, 1e5), doc="primary image motion limit at speed_max")
    dark_fraction: float = num(0.05, gt=0, lt=1, plausible=(1e-4, 0.99), doc="dark signal over t_secondary at max temperature")
    headlight_max: float = num(0.9, gt=0, le=1, plausible=(0.01, 1.0), doc="headlight signal below this fraction of swing")
    headlight_snr: float = num(10.0, gt=0, plausible=(0.1, 1e6), doc="headlight signal over the secondary's noise floor")
    margin: float = num(0.05, gt=0, lt=0.5, plausible=(1e-4, 0.5),
                        doc="relative margin required on every inequality (> 0: a design on a bound has none)")


@dataclass(frozen=True)
class Light:
    """Where the kit's light figures come from (docs/light-collection.md)."""
    model: str = text("geometric", choices=("geometric", "modelled"),
                      doc="geometric: the secondary's photocurrent is the primary's density times the mask opening, "
                          "the storage node collects 1/pixel.gse of its photodiode's, the light map's junctions "
                          "their exposed area times the QE; modelled: all three from the collection model of the "
                          "drawn pixel (absorption by wavelength, the light field under the metals, diffusion "
                          "to each junction) over the scene's spectrum (the technology needs a [collection] table)")
    wavelength_min: float = qty("m", 400e-9, gt=0, plausible=(250e-9, 1200e-9),
                                doc="shortest wavelength the collection model computes (the silicon table: 250 - 1200 nm)")
    wavelength_max: float = qty("m", 1100e-9, gt=0, plausible=(250e-9, 1200e-9), doc="longest wavelength it computes")
    wavelength_step: float = qty("m", 25e-9, gt=0, plausible=(1e-9, 200e-9), doc="wavelength step")
    grid: float = qty("m", 0.25e-6, gt=0, plausible=(0.05e-6, 2e-6),
                      doc="lateral spacing of the collection grid (the cell's sides must be multiples of it; the "
                          "light field runs on a grid twice as fine where the wavelength needs it)")
    depth: float = qty("m", 30e-6, gt=0, plausible=(2e-6, 1e-3),
                       doc="depth of the 3D grid; below it the collection is laterally uniform and joined exactly")
    source_factor: float = num(1000.0, gt=1, plausible=(1.0, 1e9),
                               doc="the bright source of the storage-light figures (verify storage_light_*): its "
                                   "photocurrent in each subpixel over the background's (the sizing's), lit while the "
                                   "frame is read out only (an LED headlight's PWM off during the exposure)")
    max_readout_error: str = text("1x", doc="the light map's limit (pixelkit lightmap, the report's light-map "
                                            "section, the datasheet): each column's AFE output error from the light "
                                            "on the readout's open junctions, as a multiple of the read noise there "
                                            "(\"1x\": visible in a single frame beyond it) or a voltage (\"2 mV\")")

    def validate(self, path, source, raw):
        from .verify.light import parse_limit
        parse_limit(self.max_readout_error, source, f"{path}.max_readout_error")
        if self.wavelength_max <= self.wavelength_min:
            raise ConfigError(source, f"{path}.wavelength_max", as_written(raw, "wavelength_max", self.wavelength_max),
                              f"a wavelength above wavelength_min ({as_written(raw, 'wavelength_min', '')})")


@dataclass(frozen=True)
class LayoutRef:
    gds: str = text(doc="GDS file (relative to the design file) whose extracted geometry the models use")


@dataclass(frozen=True)
class Design:
    name: str = ident(doc="design name: the report folder, netlist and GDS cell names (reaches netlists, so "
                          "letters, digits and _ only)")
    revision: str = text(doc="chip revision label, shown in the report and compared by the revision diff")
    technology: str = text(doc="a built-in technology name or a path to a .toml file")
    primary: Subpixel = table(Subpixel, doc="the primary subpixel and its array (records the scene)")
    secondary: Subpixel = table(Subpixel, doc="the secondary subpixel and its array (records the bright trace)")
    pixel: Pixel = table(Pixel, doc="what both subpixels share: swing, SF bias, reset levels, devices")
    afe: Afe = table(Afe, doc="the switched-capacitor double-sampling column AFE")
    family: str = text("dual_pixel", choices=("dual_pixel",),
                       doc="pixel family; the others (wdr, ratio) load through pixelkit/family.py")
    corner: str = ident("", doc="model corner; empty = the technology's default")
    temperature: float = qty("K", 300.15, gt=0, lt=500, plausible=(213.15, 473.15),
                             doc="die temperature of every simulation and model (dark current, kT/C, devices)")
    secondary_per_pixel: int = integer(3, ge=1, le=16,
                                       doc="secondary subpixels per integrated pixel (side by side under one primary)")
    experiment: Experiment = table(Experiment, default=Experiment, doc="the same-window simulation experiment")
    optics: Optics | None = table(Optics, None, doc="the lens (sizing and frame models)")
    scene: Scene | None = table(Scene, None, doc="the measurement scene (sizing and frame models)")
    sizing: Sizing = table(Sizing, default=Sizing, doc="the sizing criteria and bounds")
    layout: LayoutRef | None = table(LayoutRef, None, doc="a GDS whose extracted geometry replaces the drawn one")
    light: Light = table(Light, default=Light, doc="the light model: geometric openings or the collection model of the "
                                                   "drawn pixel (docs/light-collection.md)")
    verify: VerifySettings = table(VerifySettings, default=VerifySettings,
                                   doc="the sign-off grid of pixelkit verify: corners, temperatures, supplies, Monte Carlo")
    spec: tuple = named(Spec, doc="specifications: one [spec.<name>] table each (docs/verify.md)")
    close: CloseSettings | None = table(CloseSettings, None, doc="the knobs pixelkit close may move, their bounds "
                                        "and the objective (docs/close.md)")
    tech: Technology = field(default=None, metadata=dict(kind="skip"))
    source: str = field(default="", metadata=dict(kind="skip"))
    raw: dict = field(default=None, metadata=dict(kind="skip"), repr=False, compare=False)
    #: the extracted parasitics of the post-layout view (``layout.pex.overlay.post_layout_view``); None: schematic
    post_layout: object = field(default=None, metadata=dict(kind="skip"))

    def validate(self, path, source, raw):
        if self.pixel.swing >= 5.0:
            raise ConfigError(source, "pixel.swing", as_written(raw, "pixel.swing", self.pixel.swing),
                              "a swing below 5 V")
        n = self.secondary_per_pixel
        if abs(n * self.secondary.pitch - self.primary.pitch) > 1e-9:
            raise ConfigError(source, "secondary.pitch", as_written(raw, "secondary.pitch", self.secondary.pitch),
                              f"primary.pitch / secondary_per_pixel = {self.primary.pitch / n * 1e6:g} um "
                              "(subpixels are integrated side by side)")
        if self.close is not None:   # the knobs against this design's keys (bounds in SI)
            object.__setattr__(self, "close", check_close(self.close, self, source, raw))
        for kind in ("primary", "secondary"):
            sub, table_raw = getattr(self, kind), raw.get(kind, {})
            sub.timing.check(1.0 / sub.f_read, self.afe.nonoverlap, kind, source, table_raw)
            for key, t_exp, node in ((f"{kind}.t_int", sub.t_int, table_raw),
                                     ("experiment.t_window", self.experiment.t_window, raw.get("experiment", {}))):
                sub.timing.check_exposure(t_exp, kind, source, key,
                                          as_written(node, key.split(".")[1], t_exp))

    @property
    def corner_name(self) -> str:
        return self.corner or self.tech.models.default_corner


def load_design(path: str | Path) -> Design:
    """Load and validate a design file, with its technology."""
    path = Path(path)
    raw = read_toml(path, "design")
    if raw.get("family", "dual_pixel") != "dual_pixel":  # another family: a clear refusal
        runs = ("simulate, models, regress, verify, close, netlist and report" if raw["family"] in ("pixel4t", "netlist")
                else "simulate, models and regress")
        raise ConfigError(str(path), "family", raw["family"], f"a dual-pixel design for this command (a "
                          f"{raw['family']} design runs with {runs})")
    design = load(Design, raw, "", str(path))
    tech = load_technology(design.technology, relative_to=path.parent, source=str(path))
    src = str(path)
    for f in ("v_pd_reset", "v_fd_reset"):
        if getattr(design.pixel, f) > tech.supply:
            raise ConfigError(src, f"pixel.{f}", as_written(raw, f"pixel.{f}", getattr(design.pixel, f)),
                              f"a level no higher than the supply ({tech.supply:g} V)")
    if design.pixel.gate_drive == "boosted":
        gmax = tech.mos.v_gate_max or 1.1 * tech.supply
        if design.pixel.v_gate is None:
            raise ConfigError(src, "pixel.v_gate", MISSING, "a gate level with gate_drive = \"boosted\" (the "
                              f"boosted rail, at most {gmax:.4g} V: the devices' rated gate voltage)")
        if design.pixel.v_gate > gmax:
            raise ConfigError(src, "pixel.v_gate", as_written(raw, "pixel.v_gate", design.pixel.v_gate),
                              f"a gate level no higher than the devices' rated {gmax:.4g} V (technology "
                              f"{tech.name} mos.v_gate_max{'' if tech.mos.v_gate_max else ': the supply + 10 %'})")
    elif design.pixel.v_gate is not None:
        raise ConfigError(src, "pixel.v_gate", as_written(raw, "pixel.v_gate", design.pixel.v_gate),
                          "no value with gate_drive = \"supply\" (the gates follow the supply): set "
                          "pixel.gate_drive = \"boosted\" or leave v_gate out")
    if design.afe.vref > tech.supply:
        raise ConfigError(src, "afe.vref", as_written(raw, "afe.vref", design.afe.vref),
                          f"a reference no higher than the supply ({tech.supply:g} V)")
    if tech.supply <= design.pixel.swing:
        raise ConfigError(src, "pixel.swing", as_written(raw, "pixel.swing", design.pixel.swing),
                          f"a swing below the supply ({tech.supply:g} V)")
    if design.corner and design.corner not in tech.models.corners:
        raise ConfigError(src, "corner", design.corner,
                          f"one of {', '.join(sorted(tech.models.corners))}")
    design = replace(design, tech=tech, source=str(path), raw=raw)
    check_conditions(design, tech)
    if design.layout is not None:
        design = with_layout(design, path.parent / design.layout.gds)
    if design.light.model == "modelled":   # the collection model's effective opening and GSE (cached)
        from .layout.pex.lightfigures import with_light
        design = with_light(design)
    return design


def with_layout(design: Design, gds: Path) -> Design:
    """The design with PD areas, perimeters and photoactive areas extracted from ``gds``."""
    from .layout.extract import extract
    ex = extract(gds, design.tech)
    return replace(design, primary=replace(design.primary, extracted=ex["primary"]),
                   secondary=replace(design.secondary, extracted=ex["secondary"]))
