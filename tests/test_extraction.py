"""Extraction: the process stack in the technology file, the kit's 2.5D capacitances checked against
FastCap2 (a 3D boundary-element field solver, pip ``fastcap2``) on the same drawn geometry.

Independent judge: FastCap2 solves the electrostatics of the extruded conductors; the kit's figures
come from closed forms (Sakurai-Tamaru fringe, Chern et al. coupling) over 2D region arithmetic.
The full comparison (column line, column-to-column) is ``benchmarks/extraction.py``.
"""
from dataclasses import replace

import pytest

from conftest import ROOT
from pixelkit.design import load_design
from pixelkit.errors import ConfigError, PixelkitError
from pixelkit.layout.pex import cell_geometry
from pixelkit.layout.pex import section
from pixelkit.layout.pex.capacitance import capacitances
from pixelkit.layout.pex.fastcap import clip, compare, solve
from pixelkit.tech.stack import parse_stack, require_stack

GF = ROOT / "designs" / "dual_pixel_gf180.toml"


@pytest.fixture(scope="module")
def gf():
    return load_design(GF)


@pytest.fixture(scope="module")
def dualpix(gf):
    return cell_geometry(gf, "DUALPIX")


def _window(geo, net, margin=1.5e-6):
    import klayout.db as kdb
    r = kdb.Region()
    for nets in geo.wires.values():
        if net in nets:
            r += nets[net]
    b = r.bbox()
    d = geo.dbu
    return (b.left * d - margin, b.bottom * d - margin, b.right * d + margin, b.top * d + margin)


def test_fd_node_within_15_percent_of_fastcap(gf, dualpix):
    """The secondary's FD wiring (its metal1 lane and SF gate poly with every neighbour within
    1.5 um): its total, kit vs FastCap2 on the same clipped shapes (each coupling's figures are in
    benchmarks/extraction.py; the row lines' are checked below, docs/post-layout.md says which miss)."""
    geo = clip(dualpix, _window(dualpix, "s0.fd"))
    r = compare(geo, gf.tech.stack, "s0.fd", mesh=0.4e-6)
    assert 0.3e-15 < r["total_fastcap_F"] < 1.2e-15            # a sub-fF wiring node, not a plate
    assert r["total_kit_F"] == pytest.approx(r["total_fastcap_F"], rel=0.15, abs=0)


def test_column_to_column_within_15_percent_of_fastcap(gf, dualpix):
    """4 um of the secondary's column line col_s0 between its neighbours (metal4 tracks under the
    top-metal shield): the line's total and its coupling to each neighbouring column line."""
    geo = clip(dualpix, (15e-6, 12e-6, 24.5e-6, 16e-6))
    r = compare(geo, gf.tech.stack, "col_s0", mesh=0.3e-6)
    assert r["total_kit_F"] == pytest.approx(r["total_fastcap_F"], rel=0.15, abs=0)
    pairs = {b: (k, f) for b, k, f in r["couplings"]}
    for b in ("col_p", "col_s1"):
        assert pairs[b][0] == pytest.approx(pairs[b][1], rel=0.15, abs=0), b


def _c11(gf):
    """C11 of the drawn AFE_P in a window 2 um around it: (its geometry, FastCap2's matrix of it)."""
    from pixelkit.layout.pex import chip_geometry
    g = chip_geometry(gf, ("AFE_P",))["AFE_P"]
    plate = min(g.wires["mim_top"]["vm"].each(), key=lambda p: p.bbox().bottom).bbox()
    geo = clip(g, (0.0, plate.bottom * g.dbu - 2e-6, g.bbox[2], plate.top * g.dbu + 1.5e-6))
    return geo, solve(geo, gf.tech.stack, mesh=0.4e-6)


def _surroundings(matrix, net, other):
    """``net``'s capacitance to everything but ``other`` (C11's other plate: that pair is the device)."""
    return sum(v for (a, b), v in matrix.items()
               if net in (a.split("#")[0], b.split("#")[0]) and len({a.split("#")[0], b.split("#")[0]} - {other}) == 2)


@pytest.fixture(scope="module")
def c11(gf):
    return _c11(gf)


def test_c11_top_plate_surroundings_within_15_percent_of_fastcap(gf, c11):
    """C11 of the drawn AFE_P: its top plate ``vm`` (MIM top and its metal5 strap) to everything but its
    bottom plate (that pair is the capacitor, the netlist's device), kit vs FastCap2 in a window 2 um
    around it. The strap's edge fringe lands on the bottom plate 0.9 um under it, not on the substrate
    6.1 um down: shared by area instead of area over gap the kit read +57 % (docs/post-layout.md)."""
    geo, fc = c11
    kit = _surroundings(capacitances(geo, gf.tech.stack).c, "vm", "in")
    assert 0.5e-15 < _surroundings(fc, "vm", "in") < 5e-15
    assert kit == pytest.approx(_surroundings(fc, "vm", "in"), rel=0.15, abs=0)


def test_c11_bottom_plate_surroundings_within_15_percent_of_fastcap(gf, c11, monkeypatch):
    """C11's bottom plate ``in`` (metal4, and its metal5 contact) to everything but its top plate: the top
    plate 42 nm over it, set back 0.6 um from its edges, takes the field of the bottom plate's top face
    that an isolated edge's fringe sends round the edge to the substrate (``topface``). Without that
    (the fringe of an isolated edge) the kit is 19 % over FastCap2 and the check fails."""
    import pixelkit.layout.pex.capacitance as cap
    geo, fc = c11
    truth = _surroundings(fc, "in", "vm")
    assert 2e-15 < truth < 8e-15
    assert _surroundings(capacitances(geo, gf.tech.stack).c, "in", "vm") == pytest.approx(truth, rel=0.15, abs=0)
    monkeypatch.setattr(cap, "covered_top", lambda *a: [])
    assert _surroundings(capacitances(geo, gf.tech.stack).c, "in", "vm") > 1.15 * truth


def test_row_lines_to_fd_within_15_percent_of_fastcap(gf, dualpix, monkeypatch):
    """The secondary's FD against its RS and RST row lines and its reset drain ``vrst`` (metal1 - 3 a
    few tenths of a um beside FD's short edges), each coupling kit vs FastCap2 within 15 %; without the
    corner fields (``cornerfield``: an edge to an upper conductor beside it, perpendicular and flush
    sidewalls on one layer) the same couplings are 38 - 49 % low and the check fails."""
    import pixelkit.layout.pex.capacitance as cap
    geo = clip(dualpix, _window(dualpix, "s0.fd"))
    fc = solve(geo, gf.tech.stack, mesh=0.4e-6)
    named = ("rs_s", "rst_s", "vrst")
    truth = {b: sum(v for (x, y), v in fc.items() if {x.split("#")[0], y.split("#")[0]} == {"s0.fd", b})
             for b in named}
    kit = capacitances(geo, gf.tech.stack)
    for b in named:
        assert kit.pair("s0.fd", b) == pytest.approx(truth[b], rel=0.15, abs=0), b
    monkeypatch.setattr(cap, "corner_couplings", lambda *a: None)
    monkeypatch.setattr(cap, "wedge_couplings", lambda *a: None)
    bare = capacitances(geo, gf.tech.stack)
    assert all(abs(bare.pair("s0.fd", b) / truth[b] - 1) > 0.3 for b in named)


def test_corner_field_on_a_metal1_metal3_pair_within_15_percent_of_fastcap(gf):
    """A metal1 line (0.23 um) and a metal3 line (0.38 um) 6 um long over the substrate, their facing
    edges 0.23 / 0.5 um apart in plan: the coupling kit vs FastCap2 within 15 %. The corner field's
    constant was set on the metal1 / metal2 pair (docs/post-layout.md); this pair was not used."""
    import klayout.db as kdb
    from pixelkit.layout.pex.nets import NetGeometry
    for d in (230, 500):
        geo = NetGeometry(top="pair", dbu=1e-9, bbox=(-3e-6, -1e-6, 4e-6, 7e-6),
                          wires={"metal1": {"a": kdb.Region(kdb.Box(0, 0, 230, 6000))},
                                 "metal3": {"b": kdb.Region(kdb.Box(230 + d, 0, 610 + d, 6000))}})
        fc = solve(geo, gf.tech.stack, mesh=0.3e-6)[("a", "b")]
        assert capacitances(geo, gf.tech.stack).pair("a", "b") == pytest.approx(fc, rel=0.15, abs=0), d


def _boxes(layers, bbox):
    """A NetGeometry of boxes given in um: {layer: {net: [(x0, y0, x1, y1)]}}."""
    import klayout.db as kdb
    from pixelkit.layout.pex.nets import NetGeometry
    wires = {lay: {n: kdb.Region([kdb.Box(*(int(round(v * 1000)) for v in b)) for b in bs]) for n, bs in nets.items()}
             for lay, nets in layers.items()}
    return NetGeometry(top="case", dbu=1e-9, bbox=tuple(v * 1e-6 for v in bbox), wires=wires)


def test_wedge_field_of_fd_and_its_metal1_neighbours_within_15_percent_of_fastcap(gf, dualpix, monkeypatch):
    """The secondary's FD with its metal1 neighbours alone (the other layers and the diffusions left out):
    its couplings to RST, the photodiode line, VDD, VRST and RS and its ground, kit vs FastCap2, each
    within 15 %. Most of these neighbours face FD's short edges round a corner or run on past them
    (``wedge.right_wedges``: the quarter plane opened to a half plane by w = z^2). With the quarter circles
    alone over the span both faces share (about the term before) RST, the photodiode line and VDD are
    each 22 - 26 % low and the check fails. (TG's and EC's pads, facing FD's corner diagonally, and the
    column line's corner stay 55 - 75 % low: 5.0 / 1.5 / 4.5 aF against 11 / 6 / 11.)"""
    import math

    import numpy as np

    import pixelkit.layout.pex.wedge as wedge
    geo = clip(dualpix, _window(dualpix, "s0.fd"))
    geo = replace(geo, wires={"metal1": geo.wires["metal1"]}, surface={})
    fc = solve(geo, gf.tech.stack, mesh=0.4e-6)
    named = ("0", "rst_s", "s0.pd", "vdd", "vrst", "rs_s")
    truth = {b: fc[(b, "s0.fd") if b < "s0.fd" else ("s0.fd", b)] for b in named}
    kit = capacitances(geo, gf.tech.stack)
    for b in named:
        assert kit.pair("s0.fd", b) == pytest.approx(truth[b], rel=0.15, abs=0), b
    def quarter_circles(eps, t, r0, r1, q0, q1, pair, blocks):   # over the span both faces share, unblocked
        lo, hi = np.maximum(r0, q0), np.minimum(r1, q1)
        ok = (hi > lo) & (lo > 0)
        return np.where(ok, wedge.wedge(eps, t, math.pi / 2, np.where(ok, lo, 1.0), np.where(ok, hi, 1.0)), 0.0)
    monkeypatch.setattr(wedge, "right_wedges", quarter_circles)
    bare = capacitances(geo, gf.tech.stack)
    assert all(bare.pair("s0.fd", b) < 0.8 * truth[b] for b in ("rst_s", "s0.pd", "vdd"))


def test_fringe_spread_by_distance_within_15_percent_of_fastcap(gf, monkeypatch):
    """A metal1 block (0.84 x 3 um) and a metal2 line 1 um beside it in plan (with a metal1 line of its
    net under its end): their coupling kit vs FastCap2 within 15 %. The metal2 edge's fringe strip
    (2.38 um wide) reaches over the block 0.6 um under it; shared by area over gap (a / h) the block
    took four times the substrate's share per area and the kit is 24 % over: the check fails with the
    fringe's spread by distance (``fringe.landing``) switched off."""
    import pixelkit.layout.pex.capacitance as cap
    geo = _boxes({"metal1": {"a": [(0, 0, 0.84, 3)], "b": [(1.82, -1, 2.2, 0.5)]},
                  "metal2": {"b": [(1.82, -1, 2.2, 4)]}}, (-1.5, -2.5, 3.7, 5.5))
    truth = solve(geo, gf.tech.stack, mesh=0.25e-6)[("a", "b")]
    assert capacitances(geo, gf.tech.stack).pair("a", "b") == pytest.approx(truth, rel=0.15, abs=0)
    monkeypatch.setattr(cap, "STRIPS", 0)
    assert capacitances(geo, gf.tech.stack).pair("a", "b") > 1.15 * truth


def test_corner_field_landing_under_a_third_conductor_within_15_percent_of_fastcap(gf, monkeypatch):
    """A metal1 block (3 x 0.6 um), a metal3 line 0.23 um beside its long edge in plan and another net's
    metal3 line over the block ending 0.045 um short of that edge (the secondary's FD foot under TG's
    metal3 line, RST's beside it): block to the line beside it, kit vs FastCap2 within 15 %. The corner
    field's lines from that line's sidewall land on the block's top face under the third net's line,
    which takes them (``cornerfield._landing_free``); without that the kit is 25 % over and fails."""
    import pixelkit.layout.pex.cornerfield as cf
    geo = _boxes({"metal1": {"a": [(0, 0, 3, 0.6)]},
                  "metal3": {"b": [(-0.5, 0.83, 3.5, 1.21)], "c": [(-0.5, 0.175, 3.5, 0.555)]}}, (-2, -1.5, 5, 2.7))
    truth = solve(geo, gf.tech.stack, mesh=0.25e-6)[("a", "b")]
    assert capacitances(geo, gf.tech.stack).pair("a", "b") == pytest.approx(truth, rel=0.15, abs=0)
    monkeypatch.setattr(cf, "_landing_free", lambda *a: 1.0)
    assert capacitances(geo, gf.tech.stack).pair("a", "b") > 1.15 * truth


def test_corner_field_landing_by_boxes_equals_klayout_booleans(gf, dualpix, monkeypatch):
    """The corner field's landing strips are measured by box arithmetic on layers whose boxes are exact
    (``cornerfield._Layer``: Manhattan, no two nets overlapping) and by KLayout's booleans otherwise: the
    two give the same couplings and fringe taken on the dual pixel and on a metal1 block with a metal3
    line beside it, covered by other nets' metal2 and metal3 shapes overlapping each other over the
    block (inclusion-exclusion of the cover layers) and with a metal2 line under the metal3 line. A shape
    off the axes or two nets overlapping on a layer make its boxes inexact."""
    from collections import defaultdict

    import klayout.db as kdb

    import pixelkit.layout.pex.cornerfield as cf
    from pixelkit.layout.pex.capacitance import Couplings
    stack = gf.tech.stack
    case = _boxes({"metal1": {"a": [(0, 0, 3, 0.6)]},
                   "metal2": {"c": [(0.5, 0.1, 2.5, 0.4)], "e": [(1, 0.9, 2, 1.1)]},
                   "metal3": {"b": [(-0.5, 0.83, 3.5, 1.21)], "d": [(1, 0.2, 2, 0.5), (1.8, -0.5, 2.2, 0.5)]}},
                  (-2, -1.5, 5, 2.7))

    def corner(geo):
        cpl, spent = Couplings(), defaultdict(float)
        for i in range(len(stack.conductors)):
            cf.corner_couplings(cpl, geo, stack, i, spent)
        return cpl.c, spent
    by_boxes = [corner(geo) for geo in (dualpix, case)]
    of = cf._Layer.of
    monkeypatch.setattr(cf._Layer, "of", lambda nets, merged: of(nets, merged)._replace(exact=False))
    by_booleans = [corner(geo) for geo in (dualpix, case)]
    for boxes, booleans in zip(by_boxes, by_booleans):
        for x, y in zip(boxes, booleans):
            assert x and x.keys() == y.keys()
            assert all(x[k] == pytest.approx(y[k], rel=1e-12, abs=0) for k in x)
    assert by_boxes[1][0][("a", "b")] > 0
    tilted = {"x": kdb.Region(kdb.Polygon([kdb.Point(0, 0), kdb.Point(100, 0), kdb.Point(0, 100)]))}
    overlapping = {"x": kdb.Region(kdb.Box(0, 0, 100, 100)), "y": kdb.Region(kdb.Box(50, 0, 150, 100))}
    assert not any(of(nets, cf._merged(nets)).exact for nets in (tilted, overlapping))
    assert of(case.wires["metal3"], cf._merged(case.wires["metal3"])).exact


def test_plane_index_answers_as_klayouts_booleans(dualpix):
    """``plane.Plane`` (the box index of the 2.5D terms' booleans): on every layer of the dual pixel and for
    random boxes and one slanted polygon, ``near`` gives the same intersection as the whole union,
    ``nets_near`` keeps every net the box shares area with, and ``covers`` (box arithmetic on a Manhattan
    layer) says what ``union & polygon`` says; a slanted layer is answered by the boolean."""
    import random

    import klayout.db as kdb

    from pixelkit.layout.pex.plane import Plane
    rng = random.Random(7)
    layers = [*dualpix.wires.values(), dualpix.surface,
              {"x": kdb.Region(kdb.Polygon([kdb.Point(0, 0), kdb.Point(4000, 0), kdb.Point(0, 4000)]))}]
    for nets in layers:
        plane = Plane(0.0, nets)
        b = plane.union.bbox()
        probes = [kdb.Polygon(kdb.Box(x, y, x + rng.randint(1, 3000), y + rng.randint(1, 3000)))
                  for x, y in ((rng.randint(b.left - 2000, b.right), rng.randint(b.bottom - 2000, b.top))
                               for _ in range(300))]
        probes.append(kdb.Polygon([kdb.Point(b.left, b.bottom), kdb.Point(b.right, b.bottom), kdb.Point(b.left, b.top)]))
        truth = [not (plane.union & kdb.Region(p)).is_empty() for p in probes]
        assert 0 < sum(truth) < len(truth)
        assert plane.covers(probes).tolist() == truth
        for p in probes[::10]:
            r = kdb.Region(p)
            assert (r & plane.near(r)).area() == (r & plane.union).area()
            kept = {n for n, _reg in plane.nets_near(r)}
            assert {n for n, reg in nets.items() if not (reg & r).is_empty()} <= kept


def test_lateral_section_solve_against_fastcap_on_a_pair():
    """Two metal1 lines 0.23 um wide, 0.5 um apart, 10 um long over the substrate: the coupling per
    length of the cross-section's 2D solve (``section.pair``) x 10 um against FastCap2 (3D, ends
    included) within 10 %."""
    import fastcap2 as fc
    eps, z, t, w, s = 4.0 * 8.8541878128e-12, 1.23, 0.55, 0.23, 0.5

    def prism(surf, x0, y0):
        q = surf.add_meshed_quad
        x1, y1, z0, z1 = x0 + 10, y0 + w, z, z + t
        for zz in (z0, z1):
            q((x0, y0, zz), (x1, y0, zz), (x0, y1, zz), max_dim=0.25, edge_width=0.05)
        for a, b, c in (((x0, y0, z0), (x1, y0, z0), (x0, y0, z1)), ((x0, y1, z0), (x1, y1, z0), (x0, y1, z1))):
            q(a, b, c, max_dim=0.25, edge_width=0.05)
        for a, b, c in (((x0, y0, z0), (x0, y1, z0), (x0, y0, z1)), ((x1, y0, z0), (x1, y1, z0), (x1, y0, z1))):
            q(a, b, c, max_dim=0.25)
    p = fc.Problem()
    p.perm_factor = 4.0
    a, b, g = fc.Surface(name="a"), fc.Surface(name="b"), fc.Surface(name="g")
    prism(a, 0, 0)
    prism(b, 0, w + s)
    g.add_meshed_quad((-8, -8, 0), (18, -8, 0), (-8, 8, 0), max_dim=1.5)
    for x in (a, b, g):
        p.add(x)
    m = p.solve()
    c_fc = -m[0][1] * 1e-6                     # 10 um of line, geometry in um
    c_kit = eps * section.pair(w * 1e-6, w * 1e-6, t * 1e-6, s * 1e-6, z * 1e-6)[0] * 10e-6
    assert c_kit == pytest.approx(c_fc, rel=0.10, abs=0)


@pytest.mark.parametrize("w_over_h", [5.0, 16.0])
def test_wide_fringe_solve_against_palmers_thin_strip(w_over_h):
    """The cross-section solve behind ``fringe.wide`` on a thin strip w wide, h over a ground plane, against
    Palmer's closed form (the parallel-plate capacitor by the Schwarz-Christoffel map, Trans. AIEE 56, 1937,
    with the plane as the mirror): C / eps = w / h + (2 / pi)(1 + ln(pi w / h)), good for w >> h; within 3 %.
    And Sakurai and Tamaru's edge against the solve: a 0.5 um metal1 line within 2 %, a 10 um metal3 plate
    30 % and more above it."""
    import math
    from pixelkit.layout.pex.fringe import wide
    h = 1.0e-6
    w = w_over_h * h
    palmer = w / h + (2 / math.pi) * (1 + math.log(math.pi * w / h))
    assert section.single(w, 2e-9, h) == pytest.approx(palmer, rel=0.03, abs=0)
    assert wide(0.5e-6, 0.55e-6, 1.23e-6) == pytest.approx(1.0, abs=0.02)
    assert wide(10e-6, 0.55e-6, 3.53e-6) > 1.3       # a metal3 plate 10 um wide: 1.30 / 0.93 eps per edge


def test_stack_from_the_technology_file(gf):
    st = require_stack(gf.tech)
    m1 = st.conductor("metal1")
    assert (m1.z, m1.thickness, m1.sheet) == pytest.approx((1.23e-6, 0.55e-6, 0.09), rel=1e-9, abs=0)
    assert "klayout-pex" in st.source and "Interconnect Specification" in st.source
    assert [(d.name, d.k) for d in st.dielectrics] == [("sti", 4.0), ("nitride_liner", 7.0),
                                                        ("ild_imd_oxide_passivation", 4.0), ("passivation_nitride", 7.0),
                                                        ("air", 1.0)]
    assert st.dielectrics[2].top == pytest.approx(8.5225e-6, rel=1e-9, abs=0) and st.dielectric_k == 4.0
    assert [c.name for c in st.conductors] == ["poly", "metal1", "metal2", "metal3", "metal4", "mim_top", "metal5"]
    assert st.conductor("mim_top").device_below and not m1.device_below


def test_technology_without_a_stack_is_named(ref_design):
    with pytest.raises(ConfigError) as e:
        require_stack(ref_design.tech)
    assert "stack" in str(e.value) and "c35_thesis" in str(e.value) and "post-layout" in str(e.value)


@pytest.mark.parametrize("raw, field", [
    ({"dielectric_k": 4.0, "halo": "8 um", "layers": {}}, "stack.source"),
    ({"source": "x", "dielectric_k": 0.5, "halo": "8 um", "layers": {"metal1": {}}}, "stack.dielectric_k"),
    ({"source": "x", "dielectric_k": 4.0, "halo": "8 um",
      "layers": {"metal9": {"z": "1 um", "thickness": "1 um", "sheet": "1 Ohm", "via_below": "1 Ohm"}}},
     "stack.layers.metal9"),
    ({"source": "x", "dielectric_k": 4.0, "halo": "8 um",
      "layers": {"metal1": {"z": "1 um", "thickness": "1 um", "sheet": "1 Ohm", "via_below": "1 Ohm"},
                 "metal2": {"z": "1.5 um", "thickness": "1 um", "sheet": "1 Ohm", "via_below": "1 Ohm"}}},
     "stack.layers.metal2.z"),
    ({"source": "x", "dielectric_k": 4.0, "halo": "8 um",
      "layers": {"metal1": {"z": "1 um", "thickness": "1 F", "sheet": "1 Ohm", "via_below": "1 Ohm"}}},
     "stack.layers.metal1.thickness"),
    ({"source": "x", "dielectric_k": 4.0, "halo": "8 um", "dielectrics": [{"name": "a", "k": 4.0}],
      "layers": {"metal1": {"z": "1 um", "thickness": "1 um", "sheet": "1 Ohm", "via_below": "1 Ohm"}}},
     "stack.dielectric_k"),
    ({"source": "x", "halo": "8 um", "dielectrics": [{"name": "a", "top": "1 um", "k": 4.0}, {"name": "b", "top": "0.5 um",
                                                                                          "k": 4.0}, {"name": "c", "k": 1}],
      "layers": {"metal1": {"z": "1 um", "thickness": "1 um", "sheet": "1 Ohm", "via_below": "1 Ohm"}}},
     "stack.dielectrics[1].top"),
    ({"source": "x", "halo": "8 um", "dielectrics": [{"name": "a", "top": "1 um", "k": 0.5}, {"name": "c", "k": 1}],
      "layers": {"metal1": {"z": "1 um", "thickness": "1 um", "sheet": "1 Ohm", "via_below": "1 Ohm"}}},
     "stack.dielectrics[0].k"),
    ({"source": "x", "halo": "8 um", "dielectrics": [{"name": "a", "top": "1 um", "k": 4.0}],
      "layers": {"metal1": {"z": "1 um", "thickness": "1 um", "sheet": "1 Ohm", "via_below": "1 Ohm"}}},
     "stack.dielectrics[0]"),
])
def test_bad_stack_names_the_field(raw, field):
    with pytest.raises(ConfigError) as e:
        parse_stack(raw, "t.toml", {"metal1", "metal2"})
    assert e.value.field == field


def test_every_net_is_matched_by_name(dualpix):
    """Every net with wiring carries the kit's netlist name (the LVS pairing), the shield is ground."""
    names = {n for nets in dualpix.wires.values() for n in nets}
    assert {"p.fd", "s0.fd", "s2.fd", "col_p", "col_s0", "tg_p", "rst_s", "0"} <= names
    assert dualpix.wires["metal5"].keys() == {"0"}


def test_a_layout_that_does_not_match_is_refused(gf, tmp_path):
    """Parasitics are never hung on a guessed node: a layout whose netlist differs is an error."""
    import gdstk
    from pixelkit.layout.flow import write_gds
    from pixelkit.layout.library import build_library
    lib = build_library(gf)
    cell = next(c for c in lib.cells if c.name == "SECONDARY")
    m1 = [p for p in cell.polygons if (p.layer, p.datatype) == (34, 0)]
    cell.remove(max(m1, key=lambda p: p.area()))        # cut the widest metal1 shape: an open
    path = write_gds(lib, tmp_path / "broken.gds")
    with pytest.raises(PixelkitError) as e:
        cell_geometry(gf, "DUALPIX", gds=path)
    assert "does not match" in str(e.value)


def _klayout_facing(polys, nets, halo):
    """KLayout's shielded space check (projection metrics, different nets): the reference the lateral
    pairs were taken from, as a set of (edge, edge, distance) in canonical form."""
    import klayout.db as kdb
    from pixelkit.layout.pex.capacitance import _canon
    layer = kdb.Region()
    for p, n in zip(polys, nets):
        layer.insert(kdb.PolygonWithProperties(p, {0: n}))
    pairs = layer.space_check(halo, False, kdb.Region.Projection, None, None, None, True, kdb.Region.NoOppositeFilter,
                              kdb.Region.NoRectFilter, False, kdb.Region.DifferentPropertiesConstraint)
    return {tuple(sorted((_canon(ep.first), _canon(ep.second)))) + (ep.distance(),) for ep in pairs.each()}


def _facing_set(polys, nets, halo):
    from pixelkit.layout.pex.capacitance import _canon
    from pixelkit.layout.pex.facing import facing_pairs
    out = facing_pairs(polys, nets, halo)
    got = {tuple(sorted((_canon(ep.first), _canon(ep.second)))) + (ep.distance(),) for ep in out}
    assert len(got) == len(out)      # each pair once
    return got


def _random_layer(rng, size=50, grid=100):
    """Manhattan shapes of 4 nets on a grid, one grid step apart between nets (a net's own may touch and
    merge), inside a ring of a fifth net (a polygon with a hole)."""
    import klayout.db as kdb
    owner, boxes = {}, []
    for _ in range(rng.randint(5, 50)):
        w, h = rng.randint(1, 12), rng.randint(1, 12)
        x, y, net = rng.randint(0, size - w), rng.randint(0, size - h), rng.randint(1, 4)
        cells = [(i, j) for i in range(x, x + w) for j in range(y, y + h)]
        if all(owner.get((i + a, j + b), net) == net for i, j in cells for a in (-1, 0, 1) for b in (-1, 0, 1)):
            owner.update(dict.fromkeys(cells, net))
            boxes.append((kdb.Box(x * grid, y * grid, (x + w) * grid, (y + h) * grid), net))
    regions = {n: kdb.Region() for n in range(1, 6)}
    for box, net in boxes:
        regions[net].insert(box)
    regions[5] = kdb.Region(kdb.Box(-10 * grid, -10 * grid, (size + 10) * grid, (size + 10) * grid)) - kdb.Region(
        kdb.Box(-2 * grid, -2 * grid, (size + 2) * grid, (size + 2) * grid))
    polys, nets = [], []
    for net, reg in regions.items():
        for p in reg.merged().each():
            polys.append(p)
            nets.append(net)
    return polys, nets


def test_facing_pairs_are_klayouts_shielded_space_check_on_random_layers(monkeypatch):
    """The lateral pairs computed directly (``facing.py``) are exactly KLayout's shielded space check's
    (edge parts and distances) on random Manhattan layers at halos from 3 to 80 grid steps, shielding by
    a third net, by the pair's own polygons and not by their nets' other polygons included; the shielding
    run in blocks of a few candidates (as on a large cell)."""
    import random
    from pixelkit.layout.pex import facing
    monkeypatch.setattr(facing, "_BLOCK", 2000)
    rng = random.Random(30)
    for k in range(60):
        polys, nets = _random_layer(rng)
        halo = rng.choice([300, 800, 2000, 8000])
        assert _facing_set(polys, nets, halo) == _klayout_facing(polys, nets, halo), (k, halo)


def test_facing_pairs_are_klayouts_on_the_dual_pixel(gf, dualpix):
    """The same on every layer of the drawn dual pixel at the stack's halo (the pairs its lateral coupling uses)."""
    halo = int(round(gf.tech.stack.halo / dualpix.dbu))
    for layer, nets in dualpix.wires.items():
        polys, labels = [], []
        for k, (_net, reg) in enumerate(sorted(nets.items())):
            for p in reg.each():
                polys.append(p)
                labels.append(k + 1)
        want = _klayout_facing(polys, labels, halo)
        assert _facing_set(polys, labels, halo) == want, layer
        assert want or len(nets) < 2, layer


def test_a_layer_off_the_axes_takes_klayouts_check_each_pair_once():
    """Two 45-degree strips of different nets 1 um apart: not Manhattan, so KLayout's check finds their
    facing edges (it reports the pair from each side; the extraction takes it once)."""
    import klayout.db as kdb
    from pixelkit.layout.pex.capacitance import _facing
    from pixelkit.layout.pex.facing import manhattan
    strip = [kdb.Polygon([kdb.Point(0, 0), kdb.Point(5000, 5000), kdb.Point(5000, 5500), kdb.Point(0, 500)])]
    strip.append(strip[0].moved(0, 1500))
    assert not manhattan(strip)
    pairs = _facing(strip, [1, 2], 8000)
    assert len(pairs) == 1
    assert pairs[0].distance() == pytest.approx(1000 / 2 ** 0.5, abs=2)
