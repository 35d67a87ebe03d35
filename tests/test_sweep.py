"""Sweeps: labelled results, failed points kept with ngspice's message, resume, Dask."""
import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pixelkit.circuits.testbench import dual_pixel_bench, timings
from pixelkit.errors import ConfigError
from pixelkit.measure.pixel import double_sampled
from pixelkit.spice import simulate
from pixelkit.chip.scene import default_stimulus
from pixelkit.sweep.run import run_sweep
from pixelkit.sweep.space import parse_axis, si_value

ROOT = Path(__file__).resolve().parents[1]


def test_sweep_labels_points_and_keeps_failures(ref_design):
    """Independent path for the labels: the same point simulated directly, outside the sweep.
    trtol 1e-6 makes ngspice give up ('Timestep too small'): those points must be listed with
    that message, not dropped; the signal must grow with the photocurrent."""
    d = ref_design
    s = run_sweep(d, [parse_axis("iph_p=200p,800p"), parse_axis("option.trtol=7,1e-6")], jobs=2)
    ds = s.dataset
    assert ds["signal_primary_V"].dims == ("iph_p", "option.trtol") and ds.sizes == {"iph_p": 2, "option.trtol": 2}
    assert len(s.points) == 4 and len(s.failures) == 2
    for p in s.failures:
        assert p["option.trtol"] == 1e-6 and "timestep too small" in p["message"].lower()
    ok = ds.sel({"option.trtol": 7.0})
    assert bool(ok["ok"].all()) and float(ok["signal_primary_V"][1]) > float(ok["signal_primary_V"][0]) + 0.05
    stim = default_stimulus(d, d.experiment.t_window)
    direct = simulate(dual_pixel_bench(d, 800e-12, stim["iph_s"], title="direct"))
    want = double_sampled(direct, "col_p", timings(d, d.experiment.t_window)["primary"])
    assert float(ok["signal_primary_V"].sel(iph_p=800e-12)) == pytest.approx(want, abs=1e-9)
    head = s.table().splitlines()[0].split(",")
    assert head[:3] == ["iph_p_A", "option.trtol", "signal_primary_V"] and "message" in head


def test_design_axes_and_bad_axes(ref_design):
    """A design key goes through the design schema: a value it refuses is a ConfigError
    naming the field; a corner axis runs the corner's model section."""
    with pytest.raises(ConfigError, match="sf_bias"):
        run_sweep(ref_design, [parse_axis("pixel.sf_bias=5 A")])
    with pytest.raises(ConfigError, match="NAME=VALUES"):
        parse_axis("iph_p")
    with pytest.raises(ConfigError, match=">= 0"):
        parse_axis("iph_p=-1n")
    assert si_value(ref_design, "pixel.sf_bias") == (pytest.approx(1e-6), "A")   # the design file's "1 uA"
    assert si_value(ref_design, "corner") is None
    s = run_sweep(ref_design, [parse_axis("corner=ss,ff")], jobs=2)
    rst = s.dataset["reset_primary_V"]
    # slow NMOS: higher SF threshold, lower column reset level than fast
    assert float(rst.sel(corner="ss")) < float(rst.sel(corner="ff")) - 0.02


_GATE = """#!/bin/sh
# ngspice on the sweep's PATH: simulations 1-3 run the real ngspice; the 4th marks itself in
# flight and waits to be killed, so the interrupt lands with exactly 3 points finished.
case "$1" in -b) ;; *) exec "{real}" "$@" ;; esac
n=$(flock "{d}/lock" sh -c 'n=$(( $(cat "{d}/count" 2>/dev/null || echo 0) + 1 )); echo $n > "{d}/count"; echo $n')
[ "$n" -le 3 ] && exec "{real}" "$@"
touch "{d}/held.$$"
exec tail -f /dev/null
"""


def test_interrupted_sweep_resumes_without_recomputing(tmp_path):
    """Interrupt a real `pixelkit sweep`, run it again: the second run simulates exactly the
    points the first did not finish (cache entries counted on disk: the independent record of
    what finished). No timing: an ngspice gate on the sweep's PATH lets 3 simulations through and
    holds the 4th until it is killed; the test waits for that hold, then sends Ctrl-C."""
    import shutil
    from conftest import wait_for
    gate = tmp_path / "gate"
    gate.mkdir()
    (gate / "ngspice").write_text(_GATE.format(real=shutil.which("ngspice"), d=gate))
    (gate / "ngspice").chmod(0o755)
    env = dict(os.environ, PIXELKIT_CACHE=str(tmp_path / "cache"), PIXELKIT_PROGRESS="0")
    args = [sys.executable, "-m", "pixelkit", "sweep", "designs/dual_pixel_revA.toml", "--over",
            "iph_p=lin:100p:1.5n:8", "--jobs", "1", "--out", str(tmp_path / "o"), "--json"]
    p = subprocess.Popen(args, cwd=ROOT, env=dict(env, PATH=f"{gate}:{env['PATH']}"),
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)

    def held():
        assert p.poll() is None, "the sweep ended before its 4th simulation"
        return any(gate.glob("held.*"))
    wait_for(held, "the 4th simulation held by the gate")
    held_pid = next(gate.glob("held.*")).name.split(".")[1]
    p.send_signal(signal.SIGINT)
    p.communicate(timeout=600)
    assert p.returncode == 130
    wait_for(lambda: not os.path.exists(f"/proc/{held_pid}"), "the held ngspice to be killed")
    sim = tmp_path / "cache" / "sim"
    assert len(list(sim.glob("*/*.entry"))) == 3
    q = subprocess.run(args, cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    assert q.returncode == 0, q.stderr
    r = json.loads(q.stdout)
    assert r["computed"] == 5
    assert sum(pt["cached"] for pt in r["points"]) == 3
    sig = [pt["signal_primary_V"] for pt in r["points"]]
    assert np.all(np.diff(sig) > 0)


def test_dask_cluster_gives_the_local_numbers(ref_design, tmp_path, monkeypatch):
    """Independent reference: the same points simulated by the local executor from a second,
    empty cache of its own (the Dask workers write only to the first, so neither run can read
    the other's results). A Dask LocalCluster (2 worker processes) started here runs the sweep."""
    from dask.distributed import LocalCluster
    dask_cache, local_cache = tmp_path / "dask_cache", tmp_path / "local_cache"
    monkeypatch.setenv("PIXELKIT_CACHE", str(dask_cache))       # the workers inherit it at start
    axes = [parse_axis("iph_p=150p,600p"), parse_axis("iph_s=20p,60p")]
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        remote = run_sweep(ref_design, axes, scheduler=cluster.scheduler_address)
    assert not remote.failures and not any(p["cached"] for p in remote.points)
    assert len(list((dask_cache / "sim").glob("*/*.entry"))) == 4      # the workers did the work
    monkeypatch.setenv("PIXELKIT_CACHE", str(local_cache))
    local = run_sweep(ref_design, axes, jobs=2)
    assert not local.failures and not any(p["cached"] for p in local.points)  # computed again, here
    assert len(list((local_cache / "sim").glob("*/*.entry"))) == 4
    for f in ("signal_primary_V", "signal_secondary_V", "reset_primary_V"):
        assert np.allclose(remote.dataset[f].values, local.dataset[f].values, rtol=0, atol=1e-9), f
    assert float(local.dataset["signal_secondary_V"].sel(iph_p=150e-12, iph_s=60e-12)) > \
        float(local.dataset["signal_secondary_V"].sel(iph_p=150e-12, iph_s=20e-12))
