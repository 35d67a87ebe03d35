"""The conversion gain stage by stage: the PD / FD sharing during the transfer, TG's turn-off (the TG
charge split) and RS's turn-on (the select switch), analytic (``physics.fd.transfer``) against the FD
voltage per electron in SPICE at each stage (a known photo-charge against a dark run, the GF180
dual-pixel bench, schematic and post-layout).

The former single-capacitance model, q / (C_PD,node + C_FD,read), is 3.5 % (primary) and 10 %
(secondary) off at the transfer and lands near SPICE at the read only because the two switch
errors cancel: the test shows that too, so each stage is checked on its own.
"""
import pytest

from conftest import ROOT
from pixelkit.camera.spicenoise import sf_gain
from pixelkit.circuits.testbench import dual_pixel_bench, timings
from pixelkit.constants import Q
from pixelkit.design import load_design
from pixelkit.layout.pex.overlay import post_layout_view
from pixelkit.physics import fd
from pixelkit.spice import simulate_many
from pixelkit.techfit.ekv import models_for

GF = ROOT / "designs" / "dual_pixel_gf180.toml"
N_E = {"primary": 20000, "secondary": 5000}
INST = {"primary": "xp", "secondary": "xs0"}


def _spice_stages(d):
    tw = d.experiment.t_window
    dark, step = simulate_many([dual_pixel_bench(d, 0.0, 0.0, title="stages_dark"),
                                dual_pixel_bench(d, N_E["primary"] * Q / tw, N_E["secondary"] * Q / tw,
                                                 title="stages_step")])
    out = {}
    for w in ("primary", "secondary"):
        t, node = timings(d, tw)[w], f"x1.{INST[w]}.fd"
        at = {"transfer": t.t_tx - 10e-9, "store": t.row(0) + t.phase("rs_on") - 20e-9, "read": t.t_signal(0)}
        out[w] = {k: (dark.at(node, x) - step.at(node, x)) / N_E[w] for k, x in at.items()}
    return out


#: the rows of docs/post-layout.md's stage table: (design file, post-layout view)
VIEWS = {"dual_pixel_gf180": (GF, False), "dual_pixel_gf180, post-layout": (GF, True),
         "dual_pixel_revA": (ROOT / "designs" / "dual_pixel_revA.toml", False)}


@pytest.fixture(scope="module")
def stages():
    """{view: {subpixel: (the model's stages, SPICE's stages, the former single-capacitance CG)}}."""
    out = {}
    for view, (path, post) in VIEWS.items():
        d = load_design(path)
        d = post_layout_view(d) if post else d
        a = sf_gain(d)
        sp = _spice_stages(d)
        out[view] = {w: (fd.transfer(d, w, a, models_for(d)), sp[w], Q / fd.capacitances(d, w, a)["c_total_F"])
                     for w in ("primary", "secondary")}
    return out


@pytest.mark.parametrize("view", VIEWS)
def test_each_stage_against_spice(stages, view):
    for w, (m, sp, old) in stages[view].items():
        assert m["cg_transfer_V_per_e"] == pytest.approx(sp["transfer"], rel=0.01, abs=0), (w, "transfer")
        assert m["cg_store_V_per_e"] == pytest.approx(sp["store"], rel=0.02, abs=0), (w, "TG turn-off")
        assert m["cg_fd_V_per_e"] == pytest.approx(sp["read"], rel=0.02, abs=0), (w, "RS turn-on")
        # the former model: right at the read only by cancellation, wrong at the transfer
        assert abs(old / sp["transfer"] - 1) > 0.03, w


def test_post_layout_page_s_stage_table_is_the_kit_s(stages):
    """docs/post-layout.md's stage-by-stage table (``docsite/tables.py``) is the model and SPICE as above."""
    from docsite import tables
    key = {"transfer": "cg_transfer_V_per_e", "store": "cg_store_V_per_e", "read": "cg_fd_V_per_e"}
    data = {view: {w: {**{s: (m[k], sp[s]) for s, k in key.items()}, "former": old, "c_ch_F": m["c_channel_F"],
                       "eta": m["eta"]} for w, (m, sp, old) in by.items()}
            for view, by in stages.items()}
    bad = tables.hold("transfer-stages", data)
    assert not bad, bad
