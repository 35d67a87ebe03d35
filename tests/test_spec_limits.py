"""Every derived spec limit of the shipped designs, recomputed by a path the figure does not take.

The PD-referred conversion gain's limits (``pd_conversion_gain_*``) are q / C_PD,node at the PD reset
level +-10 %, derived in the spec's note from the kit's analytic junction and diffusion model
(``physics.nodes.pd_node``). Here C_PD,node comes from ngspice instead: the node (the PD junction's
card, the EC and TG transistors with their BSIM4 junctions and overlaps, gates at 0 V) driven by a
slow voltage ramp, C = I / (dV/dt) - the devices' own charge models, not the kit's formulas.

The full well at the column (``full_well_*``: column swing / CG_out(0)) is derived in the note as
V_col(V_FD,dark) / (A_sf q / C_total). Recomputed here from: the dark FD level read from the dark
frame's transient (the FD node, not the column the figure reads), the follower's DC operating point
there (V_col and A_sf from +-50 mV), and C_total from one ramped node carrying everything the
shared charge sees at the read (PD junction, EC, TG, RST diffusions, the selected follower's gate).
No analytic capacitance and no small-signal transient of the figure's own bench enters.

And every other spec's note says where its limit comes from; the revisions carry the [Thesis2019] chip's
(revA's) derived limits unchanged.
"""
import tomllib

import pytest

from conftest import REF, ROOT
from pixelkit.constants import Q
from pixelkit.design import load_design
from pixelkit.spice.netlist import Element, Pwl, Tran

DESIGNS = {"revA": REF, "thesis_read": ROOT / "designs" / "dual_pixel_revA_thesis_read.toml"}
RAMP_T, RAMP_DV = 1e-6, 0.05
#: the derivations' figures (``NAME.WHICH.KEY``), filled by the tests below, quoted by docs/revisions.md (``lim:``)
MEASURED: dict = {}


def _ramped_capacitance(design, elements, v: float, title: str) -> float:
    """C (F) of node ``n`` at ``v``: a linear ramp v + dv -> v - dv over RAMP_T, C = I / (dV/dt) at v."""
    from pixelkit.circuits.testbench import _deck
    from pixelkit.spice import simulate_many
    ramp = Pwl(((0.0, v + RAMP_DV), (0.2 * RAMP_T, v + RAMP_DV), (1.2 * RAMP_T, v - RAMP_DV)))
    net = _deck(design, title, [*elements, Element("Vn", ("n", "0"), ramp)], (), Tran(1e-9, 1.2 * RAMP_T, 0.0, 5e-9),
                saves=("i(vn)", "n"))
    (r,) = simulate_many([net])
    # the source delivers -dQ/dt into the node: with V falling at 2 dv / T the current is +C 2 dv / T
    return float(r.at("i(vn)", 0.7 * RAMP_T)) / (2 * RAMP_DV / RAMP_T)


def _pd_node(design, which: str) -> list:
    from pixelkit.circuits.devices import mosfet, photodiode
    sub, dev, t = getattr(design, which), design.pixel.devices, design.tech
    return [photodiode("pd", "n", sub.area, sub.perimeter, t),
            Element("Vpdr", ("vpdr", "0"), design.pixel.v_pd_reset), Element("Vfd", ("fd", "0"), design.pixel.v_fd_reset),
            mosfet("ec", "vpdr", "0", "n", "0", dev.ec_w, dev.ec_l, t), mosfet("tg", "fd", "0", "n", "0", dev.tg_w, dev.tg_l, t)]


def _shared_node(design, which: str) -> list:
    """PD node and FD as one node (after the transfer they hold one voltage), the follower selected."""
    from pixelkit.circuits import column
    from pixelkit.circuits.devices import mosfet, photodiode
    sub, dev, t = getattr(design, which), design.pixel.devices, design.tech
    return [photodiode("pd", "n", sub.area, sub.perimeter, t),
            Element("Vdd", ("vdd", "0"), t.supply), Element("Vpdr", ("vpdr", "0"), design.pixel.v_pd_reset),
            Element("Vrstd", ("vrst", "0"), design.pixel.v_fd_reset),
            mosfet("ec", "vpdr", "0", "n", "0", dev.ec_w, dev.ec_l, t), mosfet("tg", "n", "0", "n", "0", dev.tg_w, dev.tg_l, t),
            mosfet("rst", "vrst", "0", "n", "0", dev.rst_w, dev.rst_l, t),
            mosfet("sf", "vdd", "n", "sfo", "0", dev.sf_w, dev.sf_l, t), mosfet("rs", "sfo", "vdd", "col", "0", dev.rs_w, dev.rs_l, t),
            *column.bias(design), *column.load(design, "col")]


def _specs(path) -> dict:
    from pixelkit.units import quantity
    raw = tomllib.loads(path.read_text())["spec"]
    dims = {"pd_conversion_gain": "V/C", "full_well": "C"}
    out = {}
    for name, s in raw.items():
        dim = next((d for k, d in dims.items() if name.startswith(k)), None)
        if dim:
            out[name] = {k: quantity(s[k], dim, k, "t") for k in ("min", "max", "typ") if k in s}
    return out


@pytest.mark.parametrize("which", ["primary", "secondary"])
@pytest.mark.parametrize("name", list(DESIGNS))
def test_pd_conversion_gain_limits_are_the_node_at_its_reset(name, which):
    d = load_design(DESIGNS[name])
    c = _ramped_capacitance(d, _pd_node(d, which), d.pixel.v_pd_reset, f"lim_pd_{which[0]}")
    s = _specs(DESIGNS[name])[f"pd_conversion_gain_{which}"]
    assert s["typ"] == pytest.approx(1.0 / c, rel=0.01)       # V/C: q / C per electron
    assert s["min"] == pytest.approx(0.9 * s["typ"], rel=0.002) and s["max"] == pytest.approx(1.1 * s["typ"], rel=0.002)
    # the thesis's table value (the bare junction at 2.5 V) lies outside the node's window
    bare = _ramped_capacitance(d, _pd_node(d, which)[:1], 2.5, f"lim_bare_{which[0]}")
    MEASURED.setdefault(name, {}).setdefault(which, {}).update({"pd_cg_uV_per_e": Q / c * 1e6, "bare_cg_uV_per_e": Q / bare * 1e6})
    assert Q / bare == pytest.approx({"primary": 6.03e-6, "secondary": 21.7e-6}[which], rel=0.01)
    assert 1.0 / bare > s["max"] or which == "primary"


@pytest.mark.parametrize("which", ["primary", "secondary"])
@pytest.mark.parametrize("name", list(DESIGNS))
def test_full_well_limits_are_the_column_swing_over_the_output_gain(name, which):
    from pixelkit.circuits.testbench import sf_bench
    from pixelkit.spice import simulate_many
    from pixelkit.verify import measure
    d = load_design(DESIGNS[name])
    b = measure._Bench(d)
    (dark,) = simulate_many([b.dark()])
    sub = "xp" if which == "primary" else "xs0"
    v_fd = float(dark.at(f"x1.{sub}.fd", b.tm[which].t_signal(0)))
    assert 1.6 < v_fd < d.pixel.v_fd_reset     # below the reset: the gates' feedthrough
    lo, mid, hi = simulate_many([sf_bench(d, v_fd + x, title=f"lim_sf{k}") for k, x in enumerate((-0.05, 0.0, 0.05))])
    v_col, a_sf = float(mid["v(col)"][0]), float((hi["v(col)"][0] - lo["v(col)"][0]) / 0.1)
    c_total = _ramped_capacitance(d, _shared_node(d, which), v_fd, f"lim_shared_{which[0]}")
    full_well = v_col * c_total / a_sf        # C: the swing over CG_out(0) = A_sf q / C_total, in charge
    MEASURED.setdefault(name, {}).setdefault(which, {}).update({"v_fd_V": v_fd, "v_col_V": v_col, "a_sf": a_sf,
                                                               "cg_out_uV_per_e": a_sf * Q / c_total * 1e6,
                                                               "full_well_ke": full_well / Q * 1e-3})
    s = _specs(DESIGNS[name])[f"full_well_{which}"]
    assert s["typ"] == pytest.approx(full_well, rel=0.03)
    assert s["min"] == pytest.approx(0.9 * s["typ"], rel=0.005)


def test_every_spec_says_where_its_limit_comes_from():
    for path in sorted((ROOT / "designs").glob("*.toml")):
        for name, s in tomllib.loads(path.read_text()).get("spec", {}).items():
            assert len(s.get("note", "")) > 40, f"{path.name}: spec.{name} has no derivation in its note"


def test_revisions_keep_their_revision_a_specs():
    """The closed revisions answer to their revision A's datasheet: the same specs, the same limits (the
    revision B files say so in the derived specs' notes); only the dual pixels' yield requirement is new (the 4T's
    revision B is its revision A resized to pass as drawn)."""
    for a, b in (("dual_pixel_revA", "dual_pixel_revB"), ("dual_pixel_gf180", "dual_pixel_gf180_revB"),
                 ("pixel4t_gf180", "pixel4t_gf180_revB")):
        sa, sb = (tomllib.loads((ROOT / "designs" / f"{n}.toml").read_text()) for n in (a, b))
        limits = {n: {k: v for k, v in s.items() if k != "note"} for n, s in sa["spec"].items()}
        assert limits == {n: {k: v for k, v in s.items() if k != "note"} for n, s in sb["spec"].items()}, b
        if b.startswith("dual"):   # the 4T's revision B is its revision A made to pass as drawn (no Monte Carlo)
            assert sb["verify"]["min_yield"] == "95 %" and "min_yield" not in sa["verify"]


def test_revisions_page_quotes_the_derivations():
    """docs/revisions.md quotes the derivations above (``lim:NAME.WHICH.KEY`` marks: the dark FD level, the column
    level, CG_out(0), the full well at the column, the PD node's and the bare junction's conversion gains): a change of
    the devices, the bench or the design that moves one fails here, naming the line (``PIXELKIT_DOCS_REWRITE=1``
    rewrites them). It reuses the runs above; alone it repeats revA's."""
    from docsite import figures
    for which in ("primary", "secondary"):
        if "full_well_ke" not in MEASURED.get("revA", {}).get(which, {}):
            test_full_well_limits_are_the_column_swing_over_the_output_gain("revA", which)
        if "pd_cg_uV_per_e" not in MEASURED.get("revA", {}).get(which, {}):
            test_pd_conversion_gain_limits_are_the_node_at_its_reset("revA", which)

    stale = figures.hold([ROOT / "docs" / "revisions.md"], "lim", MEASURED)
    assert not stale, "\n".join(stale)
