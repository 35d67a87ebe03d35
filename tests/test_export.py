"""Exported and golden decks run as they are in raw ngspice and give the kit's figures;
every name `pixelkit netlist --bench` accepts runs there as printed, cell libraries are refused.

Independent path: the deck file is run by ``ngspice -b -r`` in a subprocess
(no kit code: no scratch folder, no .spiceinit, no options added, no links
made), from another working directory. Its raw output, read back and measured
with the same double-sampling as the kit, must match the kit's own run within
0.1 mV. The same deck without its ``.options`` line gives signals more than 10 %
smaller (the gap the issue reported), so the check can fail.
"""
import os
import shutil
import subprocess

import numpy as np
import pytest

import pixelkit as pk
from conftest import REF, ROOT
from pixelkit.registry import BENCHES
from pixelkit.spice.raw import read_raw
from pixelkit.spice.result import Result, vector_key


def _raw_ngspice(deck, cwd):
    # one OpenMP thread, as the kit's .spiceinit sets (parallel OpenMP runs slow each other down
    # by 10x on ngspice 39); the deck itself is run as it is
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    p = subprocess.run(["ngspice", "-b", "-r", str(cwd / "out.raw"), str(deck)], cwd=cwd, env=env,
                       capture_output=True, text=True, timeout=300)
    assert (cwd / "out.raw").exists(), p.stdout[-2000:] + p.stderr[-2000:]
    data = read_raw(cwd / "out.raw")[-1]["data"]
    vectors = {vector_key(k): np.real(v) for k, v in data.items()}
    return Result(np.real(vectors.pop("time")), vectors, {})


@pytest.fixture(scope="module")
def kit(ref_design):
    return pk.measure_signals(ref_design, pk.simulate(pk.bench(ref_design, "bench_dual_pixel")))


def _worst(a, b):
    return max(abs(a[k] - b[k]) for k in a)


@pytest.mark.parametrize("models", ["absolute"])  # the link form: the golden deck below
def test_exported_deck_gives_the_kit_figures_in_raw_ngspice(tmp_path, ref_design, kit, models, cli):
    deck = tmp_path / "out" / "bench.cir"
    code, out, err = cli("netlist", REF, "--bench", "bench_dual_pixel", "--out", deck, "--models", models, "--json")
    assert code == 0, err
    run = tmp_path / "elsewhere"
    run.mkdir()
    raw = pk.measure_signals(ref_design, _raw_ngspice(deck, run))
    assert _worst(raw, kit) < 1e-4, (raw, kit)
    assert kit["primary_V"] > 0.1  # a real signal, not two zeros


def test_golden_deck_runs_as_it_is(tmp_path, ref_design, kit):
    raw = pk.measure_signals(ref_design, _raw_ngspice(ROOT / "netlists" / "bench_dual_pixel.cir", tmp_path))
    print(f"golden deck in raw ngspice vs the kit: {_worst(raw, kit) * 1e3:.4f} mV at worst")
    assert _worst(raw, kit) < 1e-4, (raw, kit)


def test_without_the_kit_options_the_deck_gives_other_figures(tmp_path, ref_design, kit):
    """The check above can fail: drop the .options line and the signals move by more than 1 mV."""
    text = (ROOT / "netlists" / "bench_dual_pixel.cir").read_text()
    bare = "\n".join(ln for ln in text.splitlines() if not ln.startswith(".options")) + "\n"
    (tmp_path / "bare.cir").write_text(bare)
    shutil.copytree(ROOT / "netlists" / "models", tmp_path / "models", symlinks=True)
    raw = pk.measure_signals(ref_design, _raw_ngspice(tmp_path / "bare.cir", tmp_path))
    for k in ("primary_V", "secondary0_V"):  # the issue measured 14 - 18 % smaller signals
        print(f"without .options: {k} {(raw[k] / kit[k] - 1) * 100:+.1f} %")
        assert raw[k] < 0.9 * kit[k], (k, raw[k], kit[k])


def test_plain_ngspice_b_prints_the_outputs(tmp_path):
    """Without -r, ngspice -b simulates only when the deck has a .print line: the export adds one."""
    p = subprocess.run(["ngspice", "-b", str(ROOT / "netlists" / "bench_pd_pair.cir")], cwd=tmp_path,
                       capture_output=True, text=True, timeout=120)
    assert "v(pdp)" in p.stdout and "no simulations run" not in p.stdout


def test_unknown_bench_is_a_user_error(cli, tmp_path):
    code, out, err = cli("netlist", REF, "--bench", "nope", "--out", tmp_path / "x.cir", "--json")
    assert code == 2
    import json
    e = json.loads(out)
    assert e["field"] == "bench" and e["value"] == "nope" and "bench_dual_pixel" in e["allowed"]
    assert not (tmp_path / "x.cir").exists()


def test_link_export_writes_the_models_link_beside_the_deck(tmp_path, cli):
    code, out, err = cli("netlist", REF, "--out", tmp_path / "d" / "b.cir", "--models", "link", "--json")
    assert code == 0, err
    link = tmp_path / "d" / "models"
    assert link.is_symlink() and (link / "sm141064.ngspice").is_file()
    assert '.lib "models/sm141064.ngspice"' in (tmp_path / "d" / "b.cir").read_text()


def _printed_tables(stdout: str) -> dict:
    """ngspice -b's own printout: {vector: [(time, value), ...]} from every 'Index time ...' table."""
    vectors, columns = {}, None
    for line in stdout.splitlines():
        tok = line.split()
        if tok[:2] == ["Index", "time"]:
            columns = tok[2:]
        elif columns and tok and tok[0].isdigit() and len(tok) == len(columns) + 2:
            for name, value in zip(columns, tok[2:]):
                vectors.setdefault(name, []).append((float(tok[1]), float(value)))
    return vectors


#: The simulated time a bench's raw run covers at most (the dual pixel's benches: 8 - 21 us, whole).
LONG_STOP = 25e-6


@pytest.mark.parametrize("name", BENCHES)
def test_every_bench_runs_in_ngspice_as_printed(tmp_path, cli, name):
    """Independent path: ngspice itself, running the command `pixelkit netlist` prints, from another
    folder: it exits 0 and its own printout holds every vector of the deck's .print line over the
    whole transient (a cell library in its place aborts with status 134). The families' sweeps are
    long (ratio 232 us, WDR 16.4 ms of transient: 41 s of ngspice CPU for the WDR deck, printed as
    text): their deck runs as printed but for the .tran stop, cut to LONG_STOP (the kit simulates
    them whole in test_wdr / test_ratio; here the point is the printed text in raw ngspice)."""
    import json
    import math
    import shlex
    code, out, err = cli("netlist", REF, "--bench", name, "--out", tmp_path / "deck" / f"{name}.cir", "--json")
    assert code == 0, err
    cmd = shlex.split(json.loads(out)["run_with"])
    assert cmd[:2] == ["ngspice", "-b"]
    deck = tmp_path / "deck" / f"{name}.cir"
    text = deck.read_text()
    wanted = [v for ln in text.splitlines() if ln.startswith(".print tran ") for v in ln.split()[2:]]
    tran = next(ln for ln in text.splitlines() if ln.startswith(".tran "))
    stop = float(tran.split()[2])
    if stop > LONG_STOP:
        stop = LONG_STOP
        deck.write_text(text.replace(tran, " ".join([*tran.split()[:2], f"{stop:g}", *tran.split()[3:]])))
    run = tmp_path / "elsewhere"
    run.mkdir()
    p = subprocess.run(cmd, cwd=run, env={**os.environ, "OMP_NUM_THREADS": "1"}, capture_output=True, text=True,
                       timeout=600)
    assert p.returncode == 0, (p.returncode, p.stdout[-1500:], p.stderr[-1500:])
    printed = _printed_tables(p.stdout)
    assert wanted and set(wanted) <= set(printed), (wanted, list(printed))
    for v in wanted:
        assert printed[v][-1][0] == pytest.approx(stop, rel=1e-6) and all(math.isfinite(x) for _, x in printed[v])


def test_only_benches_stand_alone():
    """The registry's split, from the netlists themselves: a bench has top-level elements and a
    transient; a cell library only .subckt definitions (nothing for ngspice to simulate)."""
    from pixelkit.registry import GENERATORS
    from pixelkit.design import load_design
    d = load_design(REF)
    for name, make in GENERATORS.items():
        net = make(d)
        runs = bool(net.elements) and net.analysis.kind == "tran"
        assert runs == (name in BENCHES), name


@pytest.mark.parametrize("name", ["dual_pixel", "sc_afe", "wdr_pixel"])
def test_a_cell_library_is_refused_with_the_benches(tmp_path, cli, name):
    import json
    code, out, err = cli("netlist", REF, "--bench", name, "--out", tmp_path / "x.cir", "--json")
    e = json.loads(out)
    assert code == 2 and e["field"] == "bench" and e["value"] == name and "Traceback" not in err
    assert all(b in e["allowed"] for b in BENCHES) and "cell library" in e["allowed"]
    assert not (tmp_path / "x.cir").exists()
