"""``pixelkit gap predict | diagnose`` on a pixel read by role (the 4T of designs/pixel4t_gf180.toml).

The measured data are made by ngspice with an effect the diagnosis does not model inserted into the
pixel's SPICE, never by the diagnosis's own effect library:

- an FD leakage drawn as a reverse-biased junction (a .model diode card, IS = 2 pA, from FD to ground)
  added to the generated cell; the library's ``fd_leakage`` is a current source with n_i's temperature
  law. Found: fd_leakage, its 25 degC current the diode's 2 pA at 27 degC over n_i's 27-vs-25 degC ratio
  (1.17: 1.71 pA), within 10 %;
- (slow) a raised transfer barrier written into the designer's own netlist file (designs/pixel4t_netlist's
  pix4t.spice, its Btr source's barrier 1 V -> 1.37 V by a text edit), that netlist pixel read as the
  measurement and the generator design diagnosed: transfer_barrier, +0.37 V within 10 mV.

Each with 0.1 mV of Gaussian noise per row stated in v_std_V (seeded).
"""
import csv
import json
import shutil
from dataclasses import replace

import numpy as np
import pytest

from conftest import PIXEL4T, ROOT

DESIGN = PIXEL4T
SIGMA = 1e-4
ELECTRONS = (0, 1000, 4000, 8000, 12000, 0, 0)       # in the frame read
PREVIOUS = (0, 0, 0, 0, 0, 8000, 16000)              # in the frame before (lag)


def _conditions(d):
    from pixelkit.rolepix.signal import current_for
    tw = d.experiment.t_window
    return {"i_ph_A": np.array([current_for(d, n, tw) for n in ELECTRONS]), "t_int_s": np.full(len(ELECTRONS), tw),
            "temp_C": np.full(len(ELECTRONS), 27.0),
            "i_ph_prev_A": np.array([current_for(d, n, tw) for n in PREVIOUS])}


def _write(path, table, extra=None):
    cols = {**table, **(extra or {})}
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(list(cols))
        for i in range(len(table["temp_C"])):
            w.writerow([f"{float(cols[c][i]):.9g}" for c in cols])
    return path


def _measured(design, table, extra, seed):
    from pixelkit.rolepix.gap import simulate
    v = simulate(design, table, extra=extra)
    return v + np.random.default_rng(seed).normal(0.0, SIGMA, len(v))


def _diode_leak(net, cell):
    from pixelkit.gap.circuit_edits import add_to_subckt
    from pixelkit.spice.netlist import Element, Model
    net = add_to_subckt(net, cell.subckt.name, Element("Dleak", ("0", cell.probe("fd")), "dleakgap"))
    return replace(net, models=net.models + (Model("dleakgap", "d", (("is", 2e-12), ("n", 1.0))),))


def test_gap_on_a_role_pixel_finds_an_fd_leak_injected_as_a_junction(d4t, tmp_path, cli):
    table = _conditions(d4t)
    cond = _write(tmp_path / "conditions.csv", table)
    code, out, err = cli("gap", "predict", DESIGN, "--conditions", cond, "--out", tmp_path / "pred.csv", "--json")
    assert code == 0, err
    pred = [float(r["v_nominal_V"]) for r in csv.DictReader(open(tmp_path / "pred.csv"))]
    assert pred[0] == pytest.approx(0.0, abs=1e-4) and 0.5 < pred[4] < 0.8     # dark, then 12 ke- at ~55 uV/e-
    assert pred[5] == pytest.approx(pred[0], abs=1e-4)                           # no lag at the design's barrier

    v = _measured(d4t, table, _diode_leak, seed=1)
    meas = _write(tmp_path / "measured.csv", table, {"v_V": v, "v_std_V": np.full(len(v), SIGMA)})
    code, out, err = cli("gap", "diagnose", DESIGN, "--measured", meas, "--json")
    assert code == 0, err
    r = json.loads(out)
    assert r["candidates"] == ["fd_leakage", "c_fd", "transfer_barrier", "pinning_voltage"]
    assert r["best"] == "fd_leakage" and r["explained"] and r["confident"], r["verdict"]
    assert r["verdict"].startswith("fd_leakage explains the gap")
    from pixelkit.physics.ppd import dark_scale
    assert r["fits"]["fd_leakage"]["value"] == pytest.approx(2e-12 / dark_scale(300.15, 298.15, "generation"), rel=0.1)
    assert r["nominal_p_value"] < 1e-6 and r["gap_after_rms_V"] < 2 * SIGMA < r["gap_before_rms_V"]

    # a measured file without its noise is refused, naming the column (exit 2)
    bad = _write(tmp_path / "bad.csv", table, {"v_V": v})
    code, _out, err = cli("gap", "diagnose", DESIGN, "--measured", bad)
    assert code == 2 and "v_std_V" in err, err


@pytest.mark.slow
def test_gap_on_a_role_pixel_finds_a_barrier_written_into_the_designers_netlist(d4t, tmp_path):
    from pixelkit.families.netlist.design import load_netlist_design
    from pixelkit.rolepix.gap import diagnose
    shutil.copytree(ROOT / "designs" / "pixel4t_netlist", tmp_path / "pixel4t_netlist")
    shutil.copy(ROOT / "designs" / "pixel4t_netlist.toml", tmp_path / "net.toml")
    spice = tmp_path / "pixel4t_netlist" / "pix4t.spice"
    text = spice.read_text()
    assert text.count("-1.15665233002)-1)") == 2    # the barrier in the forward and the reverse term
    spice.write_text(text.replace("-1.15665233002)-1)", "-1.15665233002)-1.37)"))
    table = _conditions(d4t)
    v = _measured(load_netlist_design(tmp_path / "net.toml"), table, None, seed=2)
    r = diagnose(d4t, {**table, "v_V": v, "v_std_V": np.full(len(v), SIGMA)})
    assert r["best"] == "transfer_barrier" and r["explained"], r["verdict"]
    assert r["fits"]["transfer_barrier"]["value"] == pytest.approx(0.37, abs=0.01)
