import subprocess
import sys
from pathlib import Path

import pytest

import strict_approx

strict_approx.install()   # approx without its 1e-12 absolute floor (tests/strict_approx.py)

ROOT = Path(__file__).resolve().parents[1]
#: The reference design: the chip of [Thesis2019] with a read that settles (issue 27).
REF = ROOT / "designs" / "dual_pixel_revA.toml"
#: The same chip with the thesis's own read (~400 nA, does not settle with the AFE): the gap module's silicon.
THESIS_READ = ROOT / "designs" / "dual_pixel_revA_thesis_read.toml"
#: The 4T pinned-photodiode pixel on GF180, read by role (issue 47).
PIXEL4T = ROOT / "designs" / "pixel4t_gf180.toml"
#: ``pixelkit report REF --quick`` exits 5: every spec the nominal condition measures passes there (the
#: reference's failures are at other conditions of its grid, docs/verify.md), and pd_dark_drop_secondary,
#: held at 85 degC only, is not run by the nominal-only profile; a report exits as verify does.
REF_QUICK_EXIT = 5
#: The specs whose waveforms the session's quick report is asked for (``--waves``): none fails at nominal.
REF_QUICK_WAVES = ("pd_conversion_gain_secondary", "full_well_primary")


@pytest.fixture(scope="session")
def ref_design():
    from pixelkit.design import load_design
    return load_design(REF)


@pytest.fixture(scope="session")
def thesis_read_design():
    from pixelkit.design import load_design
    return load_design(THESIS_READ)


@pytest.fixture(scope="session")
def d4t():
    from pixelkit.families.pixel4t.design import load_pixel4t_design
    return load_pixel4t_design(PIXEL4T)


def run_cli(*args, cwd=None, timeout=600):
    """Run ``python -m pixelkit ARGS``; return (exit code, stdout, stderr)."""
    p = subprocess.run([sys.executable, "-m", "pixelkit", *map(str, args)], capture_output=True,
                       text=True, cwd=cwd or ROOT, timeout=timeout)
    return p.returncode, p.stdout, p.stderr


@pytest.fixture
def cli():
    return run_cli


def layout_variant(path, design, cells: dict, top: str, edit):
    """The GDS (at ``path``) of ``cells`` with ``edit(shapes)`` applied to cell ``top``'s own shapes
    (a broken variant for a sign-off check to catch); the cell is left as it was."""
    from pixelkit.layout.flow import write_gds
    from pixelkit.layout.library import to_library
    cell = cells[top]
    keep = list(cell.shapes)
    cell.shapes = edit(list(cell.shapes))
    try:
        return write_gds(to_library(design, cells), path)
    finally:
        cell.shapes = keep


def wait_for(condition, what: str, within: float = 600.0):
    """Poll an observable state until ``condition()`` holds; fail naming ``what`` after ``within`` s
    (a generous bound for a loaded machine, never a guess at how long the work takes)."""
    import time
    deadline = time.monotonic() + within
    while not condition():
        assert time.monotonic() < deadline, f"waited {within:g} s for {what}"
        time.sleep(0.02)


# Simulation results are cached per test session only (real runs every session); the session's own
# cache (1 - 2 GB after the whole suite) is removed when the session ends, a given PIXELKIT_CACHE kept.
import atexit  # noqa: E402
import os  # noqa: E402
import shutil  # noqa: E402
import tempfile  # noqa: E402

if "PIXELKIT_CACHE" not in os.environ:
    os.environ["PIXELKIT_CACHE"] = tempfile.mkdtemp(prefix="pixelkit-test-cache-")
    atexit.register(shutil.rmtree, os.environ["PIXELKIT_CACHE"], ignore_errors=True)


@pytest.fixture(scope="session")
def experiment(ref_design):
    from pixelkit.experiments.thesis import run_experiment
    return run_experiment(ref_design)


@pytest.fixture(scope="session")
def thesis_read_experiment(thesis_read_design):
    from pixelkit.experiments.thesis import run_experiment
    return run_experiment(thesis_read_design)


# Tests marked ``fd_pv`` run the foundry's own decks (the GF180MCU fd_pv LVS, density and antenna
# decks), which no package registry carries: ``setup.sh`` fetches them where github.com is
# reachable. Where they are not installed those tests are deselected (never skipped silently):
# pytest's summary counts them as deselected and the line below says why.
_FD_PV_DESELECTED: list = []


def pytest_configure(config):
    config.addinivalue_line("markers", "fd_pv: runs the foundry's fd_pv decks; deselected where they are not "
                                       "installed (docs/layout-signoff.md)")


def pytest_collection_modifyitems(config, items):
    marked = [i for i in items if i.get_closest_marker("fd_pv")]
    if not marked:
        return
    from pixelkit.layout.signoff import fdpv
    why = fdpv.check()
    if why is None:
        return
    _FD_PV_DESELECTED[:] = [why, len(marked)]
    config.hook.pytest_deselected(items=marked)
    items[:] = [i for i in items if not i.get_closest_marker("fd_pv")]


def pytest_terminal_summary(terminalreporter):
    if _FD_PV_DESELECTED:
        why, n = _FD_PV_DESELECTED
        terminalreporter.write_line(f"fd_pv: {n} test(s) deselected (marker fd_pv): {why}", yellow=True)


def pd_reverse_currents(design, geometries, temperatures_K) -> dict:
    """ngspice's reverse current (A) of the technology's PD diode card at its reset bias:
    {(area, perimeter, T): I} for every geometry (area m2, perimeter m) and temperature, each deck
    with the card the kit writes for its temperature; gmin 1e-21 S (the default 1e-15 S would
    carry ~4x the c35 primary's dark current at 2.5 V)."""
    from pixelkit.circuits.devices import photodiode, photodiode_model
    from pixelkit.spice import simulate_many
    from pixelkit.spice.netlist import Element, Netlist, Op
    tech = design.tech
    keys = [(a, p, t) for a, p in geometries for t in temperatures_K]
    nets = [Netlist(title=f"pd_reverse_{k}", analysis=Op(), models=photodiode_model(tech, t),
                    elements=(Element("Vr", ("n", "0"), tech.photodiode.reset_bias), photodiode("p", "n", a, p, tech)),
                    temperature_C=t - 273.15, options=(("gmin", 1e-21),))
            for k, (a, p, t) in enumerate(keys)]
    return {key: abs(float(r["i(vr)"][0])) for key, r in zip(keys, simulate_many(nets))}


@pytest.fixture(scope="session")
def quick_report(tmp_path_factory):
    """The quick report (nominal only) of the reference design, built once per session by the command
    (umask 022, so the files' modes are checkable): (folder, exit code, stdout, stderr, the
    ``designs/*_sized.toml`` files before and after). The reference passes what the nominal condition
    measures and leaves its 85 degC spec not run, so the command exits 5 (``REF_QUICK_EXIT``); the tests
    that read the report share it."""
    out = tmp_path_factory.mktemp("quick") / "revA"
    sized = sorted((ROOT / "designs").glob("*_sized.toml"))
    old = os.umask(0o022)
    try:
        code, stdout, err = run_cli("report", REF, "--quick", "--out", out, "--waves", ",".join(REF_QUICK_WAVES))
    finally:
        os.umask(old)
    assert code == REF_QUICK_EXIT and (out / "summary.json").is_file(), err[-3000:] + stdout
    return {"out": out, "code": code, "stdout": stdout, "stderr": err, "sized": (sized, sorted(
        (ROOT / "designs").glob("*_sized.toml")))}


@pytest.fixture(scope="session")
def failing_report(tmp_path_factory, quick_report):
    """A quick report whose verdict is FAIL, for what only a failing report shows (the red banner and
    status cells, a failing spec's waveform, the datasheet's FAIL): the reference design with its
    primary full well asked above what its nominal condition gives (210 ke- against 196.7 ke-, the
    limit derived for it being 181 ke-). The same circuit as ``quick_report``, so its decks come from
    that report's simulation cache: (folder, exit code, stdout, stderr)."""
    folder = tmp_path_factory.mktemp("failing")
    text = REF.read_text()
    design = folder / "dual_pixel_revA.toml"
    design.write_text(text.replace('[spec.full_well_primary]\nmin = "181 ke-"', '[spec.full_well_primary]\nmin = "210 ke-"'))
    assert design.read_text() != text
    out = folder / "report"
    code, stdout, err = run_cli("report", design, "--quick", "--out", out)
    assert code == 1 and (out / "summary.json").is_file(), err[-3000:] + stdout
    return {"out": out, "code": code, "stdout": stdout, "stderr": err}
