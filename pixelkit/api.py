"""The documented Python API: ``import pixelkit as pk``.

The main commands of the command line are thin layers over these functions::

    import pixelkit as pk
    d = pk.load_design("designs/dual_pixel_revA.toml")     # validated, with its technology
    net = pk.bench(d, "bench_dual_pixel")                    # a testbench as a Netlist
    res = pk.simulate(net)                                   # a Result: time, vectors, meta
    sig = pk.measure_signals(d, res)                         # double-sampled column signals (V)
    pk.write_waveforms(res, "out.csv", ["col_p", "x1.xp.pd"])  # CSV (or .raw)
    pk.export_deck(d, "bench_dual_pixel", "bench.cir")       # a deck that runs in ngspice -b
    table = pk.models(d)                                     # analytic model table
    exp = pk.experiment(d)                                   # the thesis [Thesis2019] experiment (i_mid, i_5pct)
    sized = pk.size(d)                                       # mask opening, integration times
    lay = pk.layout_design(d, "layouts")                     # GDS, extraction, pictures
    gap = pk.diagnose(d, "measured.csv")                     # sim-to-real gap of measured data
    so = pk.sign_off(d, corners=("tt", "ss"), mc=20)         # [spec] over corners x T x supply, yield
    cl = pk.close_design(d, "designs/my_revB.toml")          # the [close] knobs until every spec passes

Units are SI throughout (A, V, s, m); results are plain dicts / numpy arrays.
(``measure_signals``, ``layout_design``, ``sign_off`` and ``close_design`` are not called ``measure`` / ``layout`` /
``verify`` / ``close``: those names are the subpackages ``pixelkit.measure``, ``pixelkit.layout``, ``pixelkit.verify``
and ``pixelkit.close``.)
"""
from __future__ import annotations

import warnings as _warnings
from pathlib import Path


class WorkingRangeWarning(UserWarning):
    """A design value that loads but puts the circuit outside its working range."""


def load_design(path, warn=None, drawable: bool = True):
    """Load and validate a design file; working-range findings go to ``warn`` (default: warnings.warn),
    and so (``drawable``) does a layout rule the design breaks (circuit commands run it anyway)."""
    from .design import load_design as _load
    from .working_range import check
    d = _load(path)
    messages = list(check(d))
    from .layout.fit import drawing_problem
    problem = drawing_problem(d) if drawable else None
    if problem is not None:
        messages.append(f"{problem} - `pixelkit layout` refuses this design until it is fixed; the circuit "
                        "commands run it as it is")
    for message in messages:
        if warn is None:
            _warnings.warn(message, WorkingRangeWarning, stacklevel=2)
        else:
            warn(message)
    return d


def benches() -> list[str]:
    """Names accepted by :func:`bench` (the registry's testbenches and circuits)."""
    from .registry import GENERATORS
    return list(GENERATORS)


def bench(design, name: str = "bench_dual_pixel", **kw):
    """A testbench (or circuit) of the registry as a :class:`~pixelkit.spice.Netlist`.

    ``bench_dual_pixel`` accepts ``i_primary`` / ``i_secondary`` (A) and ``with_afe``.
    """
    from .registry import bench_netlist
    return bench_netlist(design, name, **kw)


def simulate(netlist, backend: str = "batch", options=None, use_cache: bool = True):
    """Run one netlist in ngspice (cached, retried); a :class:`~pixelkit.spice.Result`."""
    from .spice import simulate as _sim
    return _sim(netlist, backend=backend, options=options, use_cache=use_cache)


def simulate_many(netlists, backend: str = "batch", jobs=None, options=None, use_cache: bool = True):
    """Run several netlists in parallel (``jobs`` workers, default ``$PIXELKIT_JOBS`` or the cores,
    at most 8), each cached and retried as :func:`simulate`; a list of Results in their order."""
    from .spice import simulate_many as _many
    return _many(netlists, backend=backend, jobs=jobs, options=options, use_cache=use_cache)


def measure_signals(design, result) -> dict:
    """Double-sampled column signals (reset - signal level, V) of a dual-pixel bench result."""
    from .circuits.testbench import timings
    from .measure.pixel import double_sampled
    tm = timings(design, design.experiment.t_window)
    out = {"primary_V": double_sampled(result, "col_p", tm["primary"])}
    for k in range(design.secondary_per_pixel):
        out[f"secondary{k}_V"] = double_sampled(result, f"col_s{k}", tm["secondary"])
    return out


def write_waveforms(result, path, vectors=None):
    """Write ``result``'s waveforms (all, or ``vectors``) to CSV, or ngspice raw if ``path`` ends in .raw."""
    from .spice.waveforms import write_waveforms as _write
    return _write(result, Path(path), vectors)


def export_deck(design, name: str, path, models: str = "absolute", **kw) -> Path:
    """Write a deck that runs as it is in ``ngspice -b`` (options, models, stimulus).

    ``models``: ``absolute`` model paths, or ``link`` (``models/<file>`` and a
    ``models`` link written beside the deck). ``name``: one of ``registry.BENCHES``
    (a cell library alone is refused: ngspice has nothing to simulate in it).
    """
    from .registry import require_bench
    from .spice.export import export_deck as _export
    require_bench(name)
    return _export(bench(design, name, **kw), Path(path), models=models)


def models(design) -> dict:
    """The analytic model table: C_jdep, conversion gain, full well, C_A, C_C."""
    from .camera.spicenoise import sf_gain
    from .physics.subpixel import model_table
    from .techfit.ekv import models_for
    return model_table(design, sf_gain(design), models_for(design))


def experiment(design, backend: str = "batch", jobs=None) -> dict:
    """The thesis's simulation experiment: i_mid, i_5pct, ratio, model vs SPICE."""
    from .experiments.thesis import run_experiment
    return run_experiment(design, backend=backend, jobs=jobs)


def size(design, out=None, sensitivity: bool = False, backend: str = "batch") -> dict:
    """Size the secondary mask opening and the integration times; writes the sized design to ``out``
    (default ``reports/<design>/<design>_sized.toml``, as the command line)."""
    from .fileio import reports_root
    from .optimize.flow import size_design
    out = Path(out) if out else reports_root() / design.name / f"{design.name}_sized.toml"
    return size_design(design, out, sensitivity, backend=backend)


def layout_design(design, out_dir="layouts", rows: int = 2, cols: int = 2, pictures: bool = True,
                  drc: bool = False, lvs: bool = False, afe: bool = False, shield: str = "full") -> dict:
    """GDS of an R x C array with its column circuits (``afe``: and AFEs) and its light shield
    (``shield``: full / pixels / none), each cell's SPICE netlist, extracted PD geometry, the junction
    left open per block, 2D/3D pictures; ``drc`` / ``lvs``: sign-off of the array under "drc" / "lvs"."""
    from .layout.flow import layout_design as _layout
    return _layout(design, Path(out_dir), rows, cols, pictures, drc=drc, lvs=lvs, afe=afe, shield=shield)


def diagnose(design, measured, seed: int = 0) -> dict:
    """Where measured data leave the simulation and which effect explains it (``pixelkit gap diagnose``)."""
    from .gap.data import read_table
    from .gap.diagnose import analyse
    from .gap.store import load_nominal
    r, _x, _resid = analyse(design, read_table(measured, design, measured=True), load_nominal(design), seed=seed)
    return r


def sign_off(design, corners=None, temperatures=None, supplies=None, mc=None, seed=None, backend: str = "batch",
           jobs=None, scheduler=None, post_layout: bool = False) -> dict:
    """The sign-off of the design's ``[spec]`` table over process corner x temperature (K) x supply
    deviation, with ``mc`` Monte Carlo samples (defaults: its ``[verify]`` table): ``rows`` (per spec:
    worst condition, value, margin, status, yield), ``failed``, ``power``, every condition's figures."""
    from .verify.run import verify as _verify
    return _verify(design, corners, temperatures, supplies, mc, seed, backend=backend, jobs=jobs,
                   scheduler=scheduler, post_layout=post_layout)


def close_design(design, out, backend: str = "batch", jobs=None, scheduler=None) -> dict:
    """``pixelkit close``: move the knobs of the design's ``[close]`` table until every ``[spec]`` passes
    at every condition of its ``[verify]`` grid with its Monte Carlo yield, optimising its objective
    (docs/close.md). Writes ``<out stem>.close.json`` (the path) beside ``out`` and, when a revision
    passes, the revision at ``out``; returns ``passes``, ``status``, the knobs, every iteration, the
    final sign-off, the yield and, when none passes, the ``conflict``."""
    from .close.revision import close_design as _close
    r = _close(design, out, backend=backend, jobs=jobs, scheduler=scheduler)
    r.pop("design_obj", None)
    return r
