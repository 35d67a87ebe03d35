import numpy as np
import pytest

from pixelkit.errors import ConfigError, SimulationError
from pixelkit.spice import Element, Netlist, Tran, simulate, simulate_many
from pixelkit.spice.netlist import Model, Subckt


def _rc(title="rc", r=1e3, extra=()):
    return Netlist(title, (Element("V1", ("a", "0"), 1.0), Element("R1", ("a", "b"), r),
                           Element("C1", ("b", "0"), 1e-9), *extra), Tran(1e-8, 5e-6, 0, 1e-8, uic=True))


def test_rc_charges_as_exp():
    r = simulate(_rc(), use_cache=False)
    assert r.at("b", 1e-6) == pytest.approx(1 - np.exp(-1), abs=2e-3)
    assert r.meta["ngspice_version"] and r.meta["wall_s"] > 0 and r.meta["options"]["gmin"] == 1e-15


def test_cache_returns_the_same_result():
    net = _rc("cached_rc", r=2e3)
    a = simulate(net)
    b = simulate(net)
    assert b.meta["cached"] and np.array_equal(a["b"], b["b"])


def test_parallel_equals_serial():
    nets = [_rc(f"par{k}", r=1e3 * (k + 1)) for k in range(4)]
    par = simulate_many(nets, jobs=2, use_cache=False)
    ser = [simulate(n, use_cache=False) for n in nets]
    for a, b in zip(par, ser):
        assert np.array_equal(a["b"], b["b"])


def test_failure_names_deck_analysis_and_ngspice_message():
    bad = _rc("broken_deck", extra=(Element("D1", ("b", "0"), "nosuchmodel"),))
    with pytest.raises(SimulationError) as e:
        simulate(bad, use_cache=False)
    msg = str(e.value)
    assert "broken_deck" in msg and ".tran" in msg and "nosuchmodel" in msg.lower()


@pytest.mark.parametrize("make", [
    lambda: Element("R1\n.control", ("a", "b"), 1.0),
    lambda: Element("X1", ("a", "b"), "sub\nshell rm -rf /"),
    lambda: Element("R1", ("a;b", "0"), 1.0),
    lambda: Element("R1", ("a", "0"), "1k\n.endc"),
    lambda: Model("pd\n.control", "d", ()),
    lambda: Subckt("s", ("a b",), ()),
    lambda: Netlist("t", (), Tran(1e-9, 1e-6), options=(("method", "gear\n.control\nshell id\n.endc"),)).text(),
    lambda: Netlist("t", (), Tran(1e-9, 1e-6), options=(("method\nshell", 1.0),)).text(),
    lambda: Element("R1", ("a", "0"), float("nan")).text(),
])
def test_nothing_injects_spice(make):
    with pytest.raises(ConfigError):
        make()


def test_design_strings_cannot_reach_a_deck(tmp_path, cli):
    """A technology whose model name tries a .control block is refused before any deck."""
    from conftest import REF, ROOT
    tech = (ROOT / "pixelkit/tech/builtin/c35_thesis.toml").read_text().replace(
        'spice_model = "pd_c35"', 'spice_model = "pd\\n.control\\nshell touch /tmp/pwned\\n.endc"')
    (tmp_path / "t.toml").write_text(tech)
    (tmp_path / "d.toml").write_text(REF.read_text().replace('"c35_thesis"', f'"{tmp_path / "t.toml"}"'))
    code, out, err = cli("simulate", tmp_path / "d.toml")
    assert code == 2 and "photodiode.spice_model" in err and "Traceback" not in err


def test_slope_and_settling_of_an_rc():
    from pixelkit.measure.pixel import discharge_slope, settling_time
    r = simulate(_rc("rc_measure"))
    tau = 1e3 * 1e-9
    # slope at the start is 1/RC (V/s), averaged over the first 2 % of tau
    assert discharge_slope(r, "v(b)", 0.0, 0.02 * tau) == pytest.approx(1 / tau * (1 - 0.01), rel=0.02)
    # settling within 1 % of the final value: tau ln(100) (final taken at 5 tau, 0.7 % short of 1 V)
    t = settling_time(r.time, r["v(b)"], 0.0, 5e-6, 0.01)
    assert t == pytest.approx(tau * np.log(1 / (0.01 + np.exp(-5))), rel=0.03)


def _start_simulation(backend, tmp_path):
    """`pixelkit simulate` on a fresh cache; returns (process, its scratch roots' glob, the pids
    simulating) once ngspice simulates: the engine marks each run in flight with a file
    ``running`` in its scratch folder holding the pid that simulates (spice/scratch.py)."""
    import glob
    import os
    import subprocess
    import sys

    from conftest import REF, ROOT, wait_for
    env = dict(os.environ, PIXELKIT_CACHE=str(tmp_path / "cache"), PIXELKIT_REPORTS=str(tmp_path / "rep"),
               PIXELKIT_PROGRESS="0")   # stderr holds only what the interrupt writes
    p = subprocess.Popen([sys.executable, "-m", "pixelkit", "simulate", str(REF), "--backend", backend],
                         cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         start_new_session=True)
    pattern = f"/tmp/pixelkit-{p.pid}-*"
    marks = f"{pattern}/*/running"
    running = []

    def in_flight():
        assert p.poll() is None, p.communicate()[1][-500:]
        for m in glob.glob(marks):
            try:
                running.append(open(m).read())
            except FileNotFoundError:  # that run has just ended
                pass
        return bool(running)
    wait_for(in_flight, "a simulation in flight")
    return p, pattern, running


def _children(pid):
    import subprocess
    return subprocess.run(["pgrep", "-P", str(pid)], capture_output=True, text=True).stdout.split()


def _gone(pids, pattern):
    """Wait until every pid has ended and no scratch root is left (workers notice their parent's
    end within 0.5 s, the watchdog removes the root once the parent's pipe closes)."""
    import glob
    import os

    from conftest import wait_for

    def ended():
        alive = [k for k in pids if os.path.exists(f"/proc/{k}") and "zombie" not in open(f"/proc/{k}/status").read()]
        return not alive and not glob.glob(pattern)
    wait_for(ended, f"processes {pids} and {pattern} to go", within=120)
    return True


@pytest.mark.parametrize("backend", ["batch", "shared"])
def test_ctrl_c_ends_cleanly(backend, tmp_path):
    """SIGINT while ngspice simulates: one line, exit 130, no worker or ngspice left, no scratch folder left."""
    import signal
    p, pattern, running = _start_simulation(backend, tmp_path)
    kids = _children(p.pid)
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=600)
    assert p.returncode == 130 and err.strip() == "pixelkit: error: interrupted", err[-500:]
    assert running and kids and _gone(set(kids) | set(running), pattern)


@pytest.mark.parametrize("backend", ["batch", "shared"])
def test_sigkill_leaves_no_workers_or_scratch(backend, tmp_path):
    """SIGKILL of the main process while ngspice simulates: its ngspice children (parent-death
    signal), shared-backend workers (they watch their parent) and scratch root (the watchdog) all go."""
    import signal
    p, pattern, running = _start_simulation(backend, tmp_path)
    kids = _children(p.pid)
    p.send_signal(signal.SIGKILL)
    p.communicate(timeout=600)
    assert running and kids and _gone(set(kids) | set(running), pattern)


@pytest.mark.parametrize("blob,what", [
    (b"Title: t\nPlotname: Transient Analysis\nFlags: real\nNo. Variables: 2\nNo. Points: 0\n"
     b"Variables:\n\t0\ttime\ttime\n\t1\tv(a)\tvoltage\nBinary:\n", "0 points"),
    (b"Title: t\nPlotname: Transient Analysis\nFlags: real\nNo. Variables: 2\nNo. Points: 10\n"
     b"Variables:\n\t0\ttime\ttime\n\t1\tv(a)\tvoltage\nBinary:\n" + b"\0" * 40, "truncated"),
    (b"Title: t\nNo. Variables: x\n", "invalid literal"),
    (b"", "no plot"),
], ids=["zero-points", "truncated", "garbage-header", "empty"])
def test_bad_raw_file_is_one_line_naming_the_file(tmp_path, blob, what):
    """An aborted transient leaves a 0-point raw file: a RawError (the engine then retries),
    never an internal error."""
    from pixelkit.spice.raw import RawError, read_raw
    f = tmp_path / "out.raw"
    f.write_bytes(blob)
    with pytest.raises(RawError) as e:
        read_raw(f)
    assert str(f) in str(e.value) and what in str(e.value) and "\n" not in str(e.value)
