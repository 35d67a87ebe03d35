"""The 4T's post-layout view: its drawn cell (layout/pixel4t.py) extracted and fed back into its benches.

Independent paths: FastCap2 (a 3D boundary-element solver) on the same drawn shapes around FD, for the
extraction; for the feed-back, the conversion gain's derivation: CG = A_sf q / C_FD, so the wiring
divides it by 1 + C_w / C_FD, C_FD the closed form of families/pixel4t/model.py at FD's read level and
C_w FD's extracted couplings (those to the follower's source and the column count 1 - A_sf of themselves:
they follow FD). SPICE's conversion gain in the view against the schematic's must fall by that ratio.
"""
import json

import pytest

from conftest import PIXEL4T

DESIGN = PIXEL4T


@pytest.fixture(scope="module")
def view(d4t):
    from pixelkit.layout.pixel4t import post_layout_view
    return post_layout_view(d4t)


def test_fd_wiring_of_the_drawn_4t_within_10_percent_of_fastcap(d4t):
    """FD's metal and poly with every neighbour within 1.5 um: the kit's 2.5D total against FastCap2's
    (measured 0.770 fF against 0.775 fF)."""
    import klayout.db as kdb
    from pixelkit.layout.pex.fastcap import clip, compare
    from pixelkit.layout.pixel4t import geometry
    geo = geometry(d4t)
    r = kdb.Region()
    for nets in geo.wires.values():
        if "fd" in nets:
            r += nets["fd"]
    b, d, m = r.bbox(), geo.dbu, 1.5e-6
    res = compare(clip(geo, (b.left * d - m, b.bottom * d - m, b.right * d + m, b.top * d + m)), d4t.tech.stack, "fd",
                  mesh=0.4e-6)
    assert 0.3e-15 < res["total_fastcap_F"] < 2e-15
    assert res["total_kit_F"] == pytest.approx(res["total_fastcap_F"], rel=0.10)


def test_the_extraction_reaches_the_simulation_as_its_derivation_says(d4t, view, tmp_path, cli):
    from pixelkit.families.pixel4t import model
    from pixelkit.rolepix.signal import signal
    pl = view.post_layout
    assert pl.couplings and pl.fd_F > 0.3e-15 and "drawn PIX4T" in pl.source
    assert all("pd" not in (a, b) for a, b, _c in pl.couplings)       # the stand-in's own wiring is not a PPD's
    assert any(e.name.startswith("Cpex") for e in view.cell().subckt.elements)
    assert not any(e.name.startswith("Cpex") for e in d4t.cell().subckt.elements)
    cg = model.conversion_gain(d4t, d4t.levels.v_rst_for(d4t.tech.supply) - 1.0)
    a = cg["a_sf"]
    c_w = sum(c * ((1 - a) if ({x, y} - {"fd"}) <= {"sfo", "col"} else 1.0) for x, y, c in pl.couplings if "fd" in (x, y))
    ratio = signal(view)["cg_V_per_e"] / signal(d4t)["cg_V_per_e"]
    assert ratio == pytest.approx(cg["c_fd_F"] / (cg["c_fd_F"] + c_w), rel=0.03)    # measured 0.749 vs 0.741
    assert ratio < 0.9
    # the closed form in the view carries the same wiring (families.pixel4t.model.wiring): SPICE within 5 %, as on
    # the schematic (tests/test_pixel4t.py)
    cg_view = model.conversion_gain(view, view.levels.v_rst_for(view.tech.supply) - 1.0)
    assert cg_view["c_fd_F"] == pytest.approx(cg["c_fd_F"] + c_w, rel=1e-9)
    assert signal(view)["cg_V_per_e"] == pytest.approx(cg_view["cg_V_per_e"], rel=0.05)

    # the command line: verify --post-layout signs off the view (the view's conversion gain, named as such)
    p = tmp_path / "p4t.toml"
    p.write_text(DESIGN.read_text().split("\n[verify]")[0] + '\n[verify]\ncorners = ["tt"]\ntemperatures = ["27 degC"]\n'
                 'supplies = ["0 %"]\nmc = 0\n\n[spec.conversion_gain]\nmin = "30 uV/e-"\nmax = "70 uV/e-"\n')
    code, out, err = cli("verify", p, "--post-layout", "--out", tmp_path / "v", "--json")
    assert code == 0, err
    r = json.loads(out)
    assert r["view"] == "post-layout"
    assert r["rows"][0]["value"] == pytest.approx(signal(view)["cg_V_per_e"] * 1e6, rel=1e-6)   # uV/e-


def test_revision_b_passes_its_conversion_gain_as_drawn_in_a_raw_ngspice_run_of_its_exported_deck(d4t, tmp_path, cli):
    """designs/pixel4t_gf180_revB.toml (RST 0.3 um wide, the follower 0.8 / 0.3 um) is revision A resized so its
    FD, wiring included, reads 50 - 70 uV/e- as drawn. Independent paths: the closed form of
    families/pixel4t/model.py in each post-layout view (revision A 44.0, revision B 57.9 uV/e-: its file's header)
    and a run of ``pixelkit netlist --bench cds --post-layout``'s deck in raw ngspice (no kit code), which must
    carry the drawn cell's wiring (its Cpex capacitors) and read B's closed form within 5 %."""
    import os
    import subprocess

    import numpy as np
    from pixelkit.circuits.cds import timing_of
    from pixelkit.families.pixel4t import model
    from pixelkit.families.pixel4t.design import load_pixel4t_design
    from pixelkit.layout.pixel4t import post_layout_view
    from pixelkit.measure.cds import cds
    from pixelkit.rolepix.export import CDS_EXPORT_E, export_benches
    from pixelkit.spice.raw import read_raw
    from pixelkit.spice.result import Result, vector_key
    rev_b = DESIGN.with_name("pixel4t_gf180_revB.toml")
    b = post_layout_view(load_pixel4t_design(rev_b))
    v_fd = b.levels.v_rst_for(b.tech.supply) - 1.0
    cg_a = model.conversion_gain(post_layout_view(d4t), v_fd)["cg_V_per_e"]
    cg_b = model.conversion_gain(b, v_fd)["cg_V_per_e"]
    assert cg_a * 1e6 == pytest.approx(43.96, abs=0.05) and cg_b * 1e6 == pytest.approx(57.82, abs=0.05)

    deck = tmp_path / "cds.cir"
    code, _out, err = cli("netlist", rev_b, "--bench", "cds", "--post-layout", "--out", deck, "--json")
    assert code == 0, err
    text = deck.read_text()
    assert all(f"Cpex{i} " in text for i in range(len(b.post_layout.couplings)))
    p = subprocess.run(["ngspice", "-b", "-r", str(tmp_path / "out.raw"), str(deck)], cwd=tmp_path, capture_output=True,
                       text=True, timeout=300, env={**os.environ, "OMP_NUM_THREADS": "1"})
    assert (tmp_path / "out.raw").exists(), p.stdout[-2000:] + p.stderr[-2000:]
    vec = {vector_key(k): np.real(v) for k, v in read_raw(tmp_path / "out.raw")[-1]["data"].items()}
    raw = Result(np.real(vec.pop("time")), vec, {})
    fr = export_benches(b)["cds"]().meta["frames"]
    out = [cds(raw, timing_of(b), fr["exposures"], fr["starts"], k, 1) for k in range(len(CDS_EXPORT_E))]
    cg = (out[1] - out[0]) / CDS_EXPORT_E[1]
    assert cg == pytest.approx(cg_b, rel=0.05)
    assert 50e-6 < cg < 70e-6


def test_the_post_layout_dark_figure_is_the_ppds_once_read_above_the_decks_step_error(d4t, view):
    """The view's 27 degC dark signal over 10 ms is 0.15 e-, ~6 uV, which the deck's ~1 uV time-step error
    on each held level moved to 8.7 e-/s (6.0 when first seen; benchmarks/pixel4t_dark_steps.py); read again
    over a longer exposure (rolepix/dark.py) it is the PPD's I_gen + I_dif (the derivation, 14.56 e-/s)
    within 3 %, as the same deck with the dark currents x100 reads it."""
    from pixelkit.circuits.pixel4t import ppd_model
    from pixelkit.constants import Q
    from pixelkit.families.pixel4t.model import tg_channel
    from pixelkit.rolepix.dark import MIN_SIGNAL_V, dark
    from pixelkit.rolepix.signal import signal
    r = dark(view)
    assert r["first_exposure_s"] == pytest.approx(d4t.array.t_int) and abs(r["first_dark_V"]) < MIN_SIGNAL_V
    assert r["exposure_s"] > 10 * d4t.array.t_int and abs(r["dark_V"]) > MIN_SIGNAL_V
    p = ppd_model(d4t, tg_channel(d4t))
    assert r["dark_V"] / signal(view)["cg_V_per_e"] / r["dt_s"] == pytest.approx((p.i_gen + p.i_dif) / Q, rel=0.03)
