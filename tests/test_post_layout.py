"""Post-layout view: the extracted wiring in the netlists every command simulates, the analytic models
taking the extracted capacitances, and the refusal of a technology without a process stack.

Independent judges: ngspice running the post-layout deck (a transient of the extracted netlist with
a known photo-charge) against the analytic conversion gain built from the same extraction; the
extraction's own totals for the bookkeeping of where each capacitance is placed.
"""
import re
import subprocess

import sys

import pytest

from conftest import ROOT, run_cli
from pixelkit.camera.spicenoise import output_cg, sf_gain
from pixelkit.design import load_design
from pixelkit.layout.pex import cell_geometry
from pixelkit.layout.pex.capacitance import capacitances
from pixelkit.layout.pex.overlay import place, post_layout_view
from pixelkit.physics import fd
from pixelkit.physics.nodes import line_cap
from pixelkit.techfit.ekv import models_for

GF = ROOT / "designs" / "dual_pixel_gf180.toml"


@pytest.fixture(scope="module")
def views():
    d = load_design(GF)
    return d, post_layout_view(d)


def test_conversion_gain_model_vs_spice_within_2_percent_post_layout(views):
    """CG_out(0) from the analytic chain with the extracted C_FD / C_PD against a SPICE charge step on
    the post-layout netlist, both arrays; the schematic model against the same SPICE runs is > 2 %
    off (the check sees the extracted wiring, it can fail)."""
    sch, post = views
    a = sf_gain(post)
    spice = output_cg(post)
    for w in ("primary", "secondary"):
        model = fd.response(post, w, a, models_for(post))["cg_out_V_per_e"]
        assert model == pytest.approx(spice[w], rel=0.02, abs=0), w
        stale = fd.response(sch, w, sf_gain(sch), models_for(sch))["cg_out_V_per_e"]
        assert abs(stale / spice[w] - 1) > 0.02, w


def test_read_start_kick_on_fd_is_the_extracted_coupling_times_the_edges(views):
    """Where the frame's read starts (EC closes again to hold the PD in reset, RS selects the row), the
    floating FD jumps. Derivation: post-layout, the jump is the schematic's own (the devices'
    charge, scaled by C_FD,store schematic / post-layout) plus the extracted wiring couplings times
    the steps on their other ends, sum C(fd, n) dV_n / C_FD,store (n: EC, RS, the PD, the column line,
    the follower's source; dV_n measured on those nodes in the same run, C_FD,store from
    ``physics.fd.transfer``). Measured: primary +19.8 mV against +22.3 predicted (the wiring's part
    77 mV of it), held to 15 % of the wiring's part, both arrays; the schematic itself drops
    (-70.6 mV on the primary), so the check sees the extraction."""
    from pixelkit.circuits.array import frame_timings
    from pixelkit.circuits.testbench import dual_pixel_bench
    from pixelkit.spice import simulate_many
    sch, post = views
    nets = [dual_pixel_bench(v, 1e-10, (3e-11,) * sch.secondary_per_pixel, with_afe=True,
                             tm=frame_timings(v, v.experiment.t_window, 1), title=f"read_kick_{k}")
            for k, v in (("sch", sch), ("post", post))]
    r_sch, r_post = simulate_many(nets)
    for w, sub, col, ctl in (("primary", "xp", "col_p", "_p"), ("secondary", "xs0", "col_s0", "_s")):
        t_read = frame_timings(post, post.experiment.t_window, 1)[w].t_read
        t0, t1 = t_read - 10e-9, t_read + 300e-9

        def jump(r, node):
            return float(r.at(f"v({node})", t1) - r.at(f"v({node})", t0))
        c = {w_: fd.transfer(v, w, sf_gain(v), models_for(v))["c_fd_store_F"] for w_, v in (("sch", sch), ("post", post))}
        cw = {frozenset((a, b)): x for a, b, x in post.post_layout.cells[f"pix5t_{w}"]}
        ends = {"ec": "ec" + ctl, "rs": "rs" + ctl, "pd": f"x1.{sub}.pd", "col": col, "sfo": f"x1.{sub}.sfo"}
        wiring = sum(cw.get(frozenset(("fd", n)), 0.0) * jump(r_post, node) for n, node in ends.items()) / c["post"]
        want = jump(r_sch, f"x1.{sub}.fd") * c["sch"] / c["post"] + wiring
        assert abs(wiring) > 0.01, w                                  # a kick the check can see
        assert jump(r_post, f"x1.{sub}.fd") == pytest.approx(want, abs=0.15 * abs(wiring)), w


def test_fd_wiring_enters_the_analytic_node(views):
    sch, post = views
    a = 0.8
    for w in ("primary", "secondary"):
        c_sch = fd.fd_node(sch, a, which=w).c_fixed
        c_post = fd.fd_node(post, a, which=w).c_fixed
        assert c_post - c_sch == pytest.approx(post.post_layout.node_wiring(w, "fd", a), rel=1e-9, abs=0)
        assert 0.3e-15 < c_post - c_sch < 2e-15      # a wiring node of a few tenths of a fF to 1 fF


def test_every_extracted_capacitance_is_placed_once(views):
    """The overlay loses and doubles nothing: what it places in the subcircuits adds up to the
    extraction's total over the dual pixel (secondaries averaged, so x3 for them)."""
    sch, _ = views
    cpl = capacitances(cell_geometry(sch, "DUALPIX"), sch.tech.stack)
    cells = place(cpl, sch.secondary_per_pixel)
    placed = (sum(c for *_, c in cells["pix5t_primary"]) + 3 * sum(c for *_, c in cells["pix5t_secondary"])
              + sum(c for *_, c in cells["dualpix"]))
    total = sum(v for (a, b), v in cpl.items() if not (a in ("0", "vss") and b in ("0", "vss")))
    # a coupling between two subpixels' nodes is placed in each (to ground in the other): counted twice
    twice = sum(v for (a, b), v in cpl.items() if "." in a and "." in b and a.split(".")[0] != b.split(".")[0])
    assert placed == pytest.approx(total + twice, rel=1e-3, abs=0)


def test_view_without_the_afes_keeps_the_pixels_wiring_and_refuses_an_afe(views):
    """``array`` without ``--afe`` asks for the view extracted without the AFEs (not drawn, not extracted):
    its pixels' and lines' wiring is the full view's (DUALPIX / DUALPIX_COL are drawn alike), it has no
    AFE wiring, and an AFE's netlist or the light map refuse it rather than run without that wiring; asked
    with the AFEs again, it is the full view (cached apart), never the one without them."""
    from pixelkit.circuits.afe import sc_afe
    from pixelkit.gap.idlelight import pattern
    sch, post = views
    bare = post_layout_view(sch, afe=False)
    assert post.post_layout.afe and post.post_layout.cells["scafe"] and post.post_layout.open_readout
    assert not bare.post_layout.afe and "scafe" not in bare.post_layout.cells and not bare.post_layout.open_readout
    for cell in ("pix5t_primary", "pix5t_secondary", "dualpix"):    # alike to the rounding of the sums' order
        b_, p_ = bare.post_layout.cells[cell], post.post_layout.cells[cell]
        assert [x[:2] for x in b_] == [x[:2] for x in p_], cell
        assert [x[2] for x in b_] == pytest.approx([x[2] for x in p_], rel=1e-12, abs=0), cell
    assert bare.post_layout.column_cap == pytest.approx(post.post_layout.column_cap, rel=1e-12, abs=0)
    for use in (sc_afe, pattern):
        with pytest.raises(ValueError, match="without the AFEs"):
            use(bare)
    assert post_layout_view(bare).post_layout == post.post_layout
    assert post_layout_view(post, afe=False).post_layout == bare.post_layout


def test_netlist_post_layout_runs_in_ngspice(tmp_path):
    out = tmp_path / "pl.cir"
    code, _, err = run_cli("netlist", GF, "--post-layout", "--out", out, timeout=300)
    assert code == 0, err
    text = out.read_text()
    body = text.split(".subckt pix5t_primary", 1)[1].split(".ends", 1)[0]
    assert re.search(r"^Cw\d+ \S*\bfd\b", body, re.M)          # FD's wiring inside the pixel subcircuit
    r = subprocess.run(["ngspice", "-b", str(out)], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert r.returncode == 0 and "error" not in r.stdout.lower(), r.stdout[-500:]


def test_technology_without_stack_refuses_post_layout():
    """revA's c35_thesis has no [stack]: --post-layout is refused naming it, never run as schematic."""
    for args in (("netlist",), ("simulate",), ("size",)):
        code, out, err = run_cli(*args, ROOT / "designs" / "dual_pixel_revA.toml", "--post-layout", timeout=120)
        assert code == 2, (args, err)
        assert "[stack]" in err and "c35_thesis" in err and "post-layout" in err


def _frame_replica(d) -> list:
    """Post-layout minus schematic double-sampled signal (mV) of each secondary of the dual-pixel bench
    (one dual pixel, its ``dualpix`` couplings, one row) read as the report's 2 x 2 frame reads dual
    pixel 0 in row 0: through the frame's S1 / S2 samplers into its AFEs, the frame's timing (EC
    holds the PDs in reset from the end of the transfer), the frame's photocurrents. At
    ``chip.frame.CONVERGED`` tolerances, as the report's frame."""
    from dataclasses import replace
    from pixelkit.chip.frame import CONVERGED
    from pixelkit.circuits.array import frame_timings
    from pixelkit.circuits.testbench import dual_pixel_bench
    from pixelkit.measure.pixel import double_sampled
    from pixelkit.report.sections.array import COLS, ROWS, default_map, photocurrents
    from pixelkit.spice import simulate_many
    sch = replace(d, post_layout=None)
    nets, tms, n = [], [], d.secondary_per_pixel
    for v in (sch, post_layout_view(sch)):
        m, unit = default_map(ROWS, n * COLS, "gradient")
        ph = photocurrents(v, ROWS, COLS, m, unit)
        tm = frame_timings(v, v.experiment.t_window, 1)
        # the frame's pixels take ph's currents during the exposure (compressed after it, when EC
        # holds the PDs in reset: only the FD's parasitic light sees the difference)
        nets.append(dual_pixel_bench(v, float(ph.iph_p[0][0]), tuple(float(ph.iph_s[0][k]) for k in range(n)),
                                     with_afe=True, tm=tm, title=f"frame_replica_{len(nets)}"))
        tms.append(tm["secondary"])
    a, b = simulate_many(nets, options=CONVERGED)
    return [1e3 * (double_sampled(b, f"col_s{k}", tms[1]) - double_sampled(a, f"col_s{k}", tms[0])) for k in range(n)]


def test_report_section_post_layout_vs_schematic(tmp_path):
    """The report's post-layout section on the GF180 design (quick profile): both views in one table,
    the post-layout FD larger than the schematic's by the extracted wiring; unavailable, saying why,
    for a technology without a stack.

    The 2 x 2 frame's shift post-layout vs schematic (dual pixel 0's three secondaries, row 0) is
    held to the same shift of the dual-pixel bench read the way the frame reads (``_frame_replica``:
    the frame's S1 / S2 samplers and AFEs on its columns, its timing with EC holding the PDs in
    reset from the end of the transfer, its row-0 photocurrents), within 0.1 mV, both at
    ``chip.frame.CONVERGED`` tolerances (measured 0.02 - 0.04 mV apart, with and without the pad stacks'
    screening, i.e. two step sequences; a 1e-3 change of the column lines' capacitance moved neither
    deck by 0.01 mV at CONVERGED). The bound sits between that and what it must catch (below).
    It was 3 mV at the default tolerances, where the frame deck itself is 0.5 - 3.9 mV off its converged
    value (a 1e-3 change of the column lines' capacitance moved it 2.3 mV) and the pad stacks' screening
    took it 3.86 mV from the replica (2.75 before) while both moved alike, -2.27 mV, at CONVERGED.
    Not against the report's pedestal bench (no AFE, EC off through the read; its secondary's
    pedestal moves by -87.1 mV, the frame's dim secondaries by -78.8 / -77.1): the two read differently,
    measured on the bench (docs/post-layout.md, the 2 x 2 frame): EC's rise kicks
    FD post-layout only, through C(fd, ec) x 3.3 V and C(fd, pd) x the PD's step to vpdr, +5.0 mV
    before the signal sample (-3.7 mV on the column); the AFE samplers +8.8 mV (the AFE's p1 opens
    20 ns before S1 and kicks the column at the signal sample, +8.1 mV on the schematic and +2.4
    post-layout in the frame, where the AFE's wiring differs); the photocurrents +1.2 mV. Row 1 is
    not held to the replica (one row): it differs from row 0 by the column's history, 1.7 - 3.4 mV.
    The check fails when the frame's column lines miss the couplings the bench's ``dualpix`` gives
    them (``column.row_share``; without it 0.17 / 0.17 / 0.05 mV apart at CONVERGED: secondaries 0
    and 1 caught)."""
    from pixelkit.report.sections import Context
    from pixelkit.report.sections import post_layout as section
    d = load_design(GF)
    s = section.build(Context(d, tmp_path, quick=True))
    rows = {r[0]: r for r in s.tables[0].rows}
    sch, post = rows["C_FD, primary (fF)"][1:3]
    assert post - sch == pytest.approx(s.tables[1].rows[0][1], rel=1e-6, abs=0)
    assert next(c for c in s.checked if c.name == "post_layout.cg_model_vs_spice_frac").value < 0.02
    # sizing on each view's curves: the opening at its bound, so t_int scales with the PD node's
    # capacitance (the same fraction of the swing is q = C dV; derivation, not the sizer's own figure)
    for w in ("primary", "secondary"):
        c_sch, c_post = rows[f"C_PD,node, {w} (fF)"][1:3]
        t_sch, t_post = rows[f"sized t_int, {w} (us) (analytic level)"][1:3]
        assert t_post / t_sch == pytest.approx(c_post / c_sch, rel=0.01, abs=0), w
    # the AFE's settling error (each row against the same read with S1 / S2 four times longer, verify's
    # figure) by value: a sampled level lies between where the column starts and where it settles, so
    # the error is below the column's swing (~0.8 V); this design does not settle at its row times
    # (issue 40: primary 163.9 mV schematic, 43.2 mV post-layout, measured), which the bound allows
    for k, w in (("500", "primary"), ("1000", "secondary")):
        got = rows[f"AFE settling error at f_read = {k} kHz, {w} (mV)"][1:3]
        assert all(0 <= x < 800 for x in got), (w, got)
    # the 2 x 2 frame (array deck) moves dual pixel 0's secondaries in row 0 by the shift of the
    # dual-pixel bench read as the frame reads them (docstring)
    frame = next(t for t in s.tables if t.name == "post_layout_frame").rows
    assert len(frame) == 2 * 2 + 2 * 2 * d.secondary_per_pixel
    rep = _frame_replica(d)
    sec = {r[2]: r[6] for r in frame if r[0] == "secondary" and r[1] == 0 and r[2] < d.secondary_per_pixel}
    for k in range(d.secondary_per_pixel):
        assert sec[k] == pytest.approx(rep[k], abs=0.1), (k, sec[k], rep[k])
    # docs/post-layout.md's section table is this section's (docsite/tables.py)
    sys.path.insert(0, str(ROOT))
    from docsite import tables
    bad = tables.hold("report-post-layout", {"rows": s.tables[0].rows, "frame": frame,
                                             "resistance": s.tables[2].rows})
    assert not bad, bad
    ref = section.build(Context(load_design(ROOT / "designs" / "dual_pixel_revA.toml"), tmp_path, quick=True))
    assert not ref.available and "[stack]" in ref.needs and "no process stack" in ref.why


def test_the_afes_floating_nodes_are_shielded_from_the_nodes_that_move(views):
    """The SC stage's op-amp input x and shared node vm hold their charge while C13 transfers it; a
    coupling from a node that moves between the phases (out, c, in) adds to the capacitor ratio, one on
    x (C11 + C12 + C13) / C12 = 3 times one on vm (GF180 revision B, extracted netlist, one coupling at a
    time: 1.2 % / fF on x, 0.4 % / fF on vm). ``layout.afe.GUARDED`` routes them first, keeps vss metal
    beside, over and under them, and steers them off other nets' landings. Here (this design, drawn
    without the guard: out-x 3.50 fF, out-vm 0.84 fF, weighted 11.3 fF; with it 0.72 / 0.85 fF, 3.0 fF):
    the weighted coupling to out below 4 fF, and x sees its shield (vss, ground) more than any moving node."""
    _sch, post = views
    cpl = {frozenset((a, b)): c for a, b, c in post.post_layout.cells["scafe"]}
    assert 3 * cpl.get(frozenset(("out", "x")), 0.0) + cpl.get(frozenset(("out", "vm")), 0.0) < 4e-15
    moving = max(cpl.get(frozenset((n, "x")), 0.0) for n in ("out", "c", "in"))
    assert cpl[frozenset(("0", "x"))] > 3 * moving


def test_post_layout_page_quotes_the_current_views(views):
    """docs/post-layout.md marks the figures of its post-layout-view table (``pl:VIEW.ARRAY.FIGURE``,
    docsite/figures.py): each is the current schematic / post-layout figure at the digits quoted (the
    SPICE charge steps are the first test's decks, served from the session's cache;
    ``PIXELKIT_DOCS_REWRITE=1`` rewrites them)."""
    import sys
    sys.path.insert(0, str(ROOT))
    from docsite import figures
    now = {}
    for name, v in zip(("sch", "post"), views):
        a, spice = sf_gain(v), output_cg(v)
        for w in ("primary", "secondary"):
            r = fd.response(v, w, a, models_for(v))
            now[f"{name}.{w}"] = {"c_fd_F": r["c_fd_F"], "c_pd_node_F": r["c_pd_node_F"],
                                  "cg_out_V_per_e": r["cg_out_V_per_e"], "cg_out_spice_V_per_e": spice[w],
                                  "model_vs_spice": r["cg_out_V_per_e"] / spice[w] - 1,
                                  "line_cap_F": line_cap(v, "col_p0" if w == "primary" else "col_s0")}
            if v.post_layout is not None:        # the extracted couplings of FD the page quotes
                cpl = {frozenset((a, b)): c for a, b, c in v.post_layout.cells[f"pix5t_{w}"]}
                now[f"{name}.{w}"].update({f"c_fd_{n}_F": cpl.get(frozenset(("fd", n)), 0.0)
                                          for n in ("rs", "rst", "tg", "vdd", "pd", "ec", "vrst")})

    def value(key):
        view, w, fig = key.split(".")
        return now[f"{view}.{w}"][fig]
    import os
    if os.environ.get("PIXELKIT_DOCS_REWRITE"):
        figures.update(None, [ROOT / "docs" / "post-layout.md"], getters={"pl": value})
    bad, n = figures.check(None, [ROOT / "docs" / "post-layout.md"], getters={"pl": value})
    assert n >= 24, n
    assert not bad, "; ".join(f"{b['page']}:{b['line']} {b['key']} quoted {b['quoted']} now "
                              f"{b.get('now') or b.get('why')}" for b in bad)
