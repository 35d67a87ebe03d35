"""One registry of generators; each emits its netlist text at the reference design's values.

The dual pixel's circuits (``circuits/``) and the other families' (``families/goldens.py``):
the registry sits above both (docs/module-layers.md).

``netlists/<name>.cir`` holds the golden copy of each; ``pixelkit netlists --write``
regenerates them and ``tests/test_golden.py`` compares every generator with its
file. Golden decks run as they are (``ngspice -b netlists/bench_dual_pixel.cir``):
they carry the kit's ``.options`` and name the model files through
``netlists/models``, a committed relative link to the model files shipped in
the package (see ``spice/export.py``).
"""
from __future__ import annotations

from pathlib import Path

from .circuits.afe import sc_afe
from .circuits.array import array_bench, pixel_array
from .circuits.devices import photodiode_model
from .circuits.dual_pixel import dual_pixel
from .circuits.opamp import macro, ota
from .circuits.pixel5t import pixel5t
from .circuits.testbench import afe_bench, dual_pixel_bench, pd_pair_bench
from .families.goldens import GENERATORS as FAMILY_GENERATORS
from .spice.netlist import Netlist, Op


def _cells(design, title, subckts) -> Netlist:
    t = design.tech
    return Netlist(title=title, elements=(), analysis=Op(), subckts=tuple(subckts),
                   models=photodiode_model(t), includes=t.models.includes(design.corner or None))


def _afe_pairs():
    return [(1.9 - dv, 1.9) for dv in (0.0, 0.4, 0.8, 1.2)]


GENERATORS = {
    "pixel5t_primary": lambda d: _cells(d, "pixel5t_primary", [pixel5t(d, "primary")]),
    "pixel5t_secondary": lambda d: _cells(d, "pixel5t_secondary", [pixel5t(d, "secondary")]),
    "dual_pixel": lambda d: _cells(d, "dual_pixel", dual_pixel(d)),
    "opamp_macro": lambda d: _cells(d, "opamp_macro", [macro(d)]),
    "opamp_ota": lambda d: _cells(d, "opamp_ota", [ota(d)]),
    "sc_afe": lambda d: _cells(d, "sc_afe", [sc_afe(d)]),
    "array_2x2": lambda d: _cells(d, "array_2x2", [*dual_pixel(d), pixel_array(d, 2, 2)]),
    "bench_dual_pixel": lambda d: dual_pixel_bench(d, 1.4e-9, 52e-12),
    "bench_dual_pixel_afe": lambda d: dual_pixel_bench(d, 1.4e-9, 52e-12, with_afe=True),
    "bench_array_2x2": lambda d: array_bench(d, [[2e-10, 4e-10], [6e-10, 8e-10]],
                                             [[1e-11 * (j + 1) for j in range(6)],
                                              [1e-11 * (j + 7) for j in range(6)]]),
    "bench_afe": lambda d: afe_bench(d, _afe_pairs()),
    "bench_pd_pair": lambda d: pd_pair_bench(d, 1e-9, 1e-9 / 3.6, 20e-6, 2.5),
}
GENERATORS.update(FAMILY_GENERATORS)  # the WDR and ratio pixels (pixelkit/families)

#: The generators whose netlist is a whole deck (stimulus, analysis, outputs): each runs alone in
#: ``ngspice -b`` (``pixelkit netlist --bench NAME``). The others are cell libraries (``.subckt``
#: definitions only, golden copies in ``netlists/``) to include in a bench of one's own.
BENCHES = ("bench_dual_pixel", "bench_dual_pixel_afe", "bench_array_2x2", "bench_afe", "bench_pd_pair",
           "wdr_sweep", "ratio_sweep")


def require_bench(name: str) -> None:
    """Refuse a name that is not a deck running alone, listing those that are."""
    from .errors import ConfigError
    if name not in BENCHES:
        what = " (a cell library: .subckt definitions only, netlists/" + name + ".cir)" if name in GENERATORS else ""
        raise ConfigError("", "bench", name, f"a deck that runs alone in ngspice -b{what}: one of {', '.join(BENCHES)}")


def bench_netlist(design, name: str, i_primary: float | None = None, i_secondary: float | None = None,
                  with_afe: bool | None = None) -> Netlist:
    """The registry's netlist ``name``; the dual-pixel benches take other photocurrents (A)."""
    from .errors import ConfigError
    if name not in GENERATORS:
        raise ConfigError("", "bench", name, f"one of {', '.join(GENERATORS)}")
    if (i_primary, i_secondary, with_afe) == (None, None, None):
        return GENERATORS[name](design)
    if name not in ("bench_dual_pixel", "bench_dual_pixel_afe"):
        raise ConfigError("", "bench", name, "bench_dual_pixel or bench_dual_pixel_afe to set photocurrents")
    afe = name.endswith("_afe") if with_afe is None else with_afe
    return dual_pixel_bench(design, 1.4e-9 if i_primary is None else i_primary,
                            52e-12 if i_secondary is None else i_secondary, with_afe=afe)


def golden_text(name: str, design) -> str:
    """The golden deck: runnable as it is (the kit's options, ``models/`` link, a ``.print`` line)."""
    from .spice.export import deck_text
    return deck_text(GENERATORS[name](design), models="link")


def write_all(design, folder: Path) -> list[Path]:
    from .fileio import write_atomic
    from .spice.export import make_link
    from .fileio import out_folder
    folder = out_folder(Path(folder), root=True)
    for link, target in GENERATORS["bench_dual_pixel"](design).model_links().items():
        make_link(Path(folder) / link, Path(target))
    return [write_atomic(folder / f"{n}.cir", golden_text(n, design)) for n in GENERATORS]
