"""Extraction checked where it was not tuned: test structures (one capacitance term each, a GDS with
labelled nets: ``pixelkit.layout.pex.structures``) extracted by ``pixelkit signoff`` and compared with
FastCap2 on the technology's layered stack, and with the PDK's own extraction coefficients.

Independent references: FastCap2 (a 3D boundary-element field solver) on the same shapes and the same
dielectric layers (GF180MCU's published table: STI, nitride liner, oxides, passivation nitride, air),
stored in tests/data/extraction_structures[_SET].json by
``python -m pixelkit.layout.pex.structures SET OUT.json`` (the slow test re-solves the first set); the
GF180MCU open PDK's area coefficients (aF/um2, as klayout-pex carries them). Ten sets
(docs/post-layout.md): ``first`` (the issue's eleven) and ``development`` were looked at while the lateral,
far-field, wide-fringe and off-axis corner terms were written; ``validation`` was held out until the
lateral and far-field terms were done, ``holdout`` until the wide fringe was, ``holdout2`` and
``holdout3`` until the far field's line ends and strip zone, ``holdout4`` until the line ends' first form
(looked at once, 9 of 12; the correction then bounded by polygon and to edges, which the AFE's plates
needed), each then looked at; ``holdout5``, drawn and solved before that last change, was compared once
and prompted the far field's images in the stack's top interface; ``holdout6``, drawn and solved before
those, compared once with the model as it is (7 of 12); ``holdout7``, drawn and solved after that look,
compared once with the model as it is (10 of 10); ``holdout8``, drawn before any change of session 6 and
compared once with the model as it is (5 of 11). None is a geometry a constant of the model was set on
(docs/post-layout.md lists those; the far field's LOCAL, 2 pitches, was chosen with the eight sets before
holdout6 in view).
"""
import json
from dataclasses import replace

import pytest

from conftest import ROOT
from pixelkit.layout.pex import capacitance
from pixelkit.layout.pex.capacitance import Couplings, float_out
from pixelkit.layout.pex.structures import REFERENCE, kit_terms, structures, term


def _ref(which):
    return json.loads((ROOT / "tests" / "data" / REFERENCE[which]).read_text())["terms_F"]


REF = _ref("first")
REFS = {w: _ref(w) for w in ("development", "validation", "holdout", "holdout2", "holdout3", "holdout4",
                          "holdout5", "holdout6", "holdout7", "holdout8")}
#: outside 10 % of FastCap2, documented (docs/post-layout.md, "what the validation set says"): the figure
#: written there (kit / FastCap2 - 1)
KNOWN_MISSES = {
    "development": {"d_cross_m1m2_45": 0.196},
    "validation": {"v_via_stack_m3": 0.155},
    "holdout": {"h_cross_m1m3_wide": 0.106, "h_cross_m2m3_30": 0.157, "h_parallel_m3m5": 0.172, "h_via_stack_m2": 0.112},
    "holdout2": {"k_cross_m1m2_45_wide": 0.234},
    "holdout3": {"q_cross_m2m3_45": 0.122},
    "holdout4": {},
    "holdout5": {"s_cross_m2m4_narrow": 0.104, "s_cross_m2m3_135": 0.160, "s_parallel_m4m5": 0.129},
    "holdout6": {"t_cross_m1m2_135_wide": 0.179, "t_parallel_m3m5_close": 0.126, "t_parallel_m2m3_far": 0.112,
                 "t_plate_m5_m4": -0.100},
    "holdout7": {},
    "holdout8": {"w_via_stack_m3_far": 0.155, "w_via_stack_m4_close": -0.110, "w_via_stack_m5_wide": 0.156,
                 "w_cross_m2m3_120_wide": 0.152, "w_cross_m3m5_45": 0.172, "w_parallel_m4m5_far": 0.182},
}
HELD = list(REF)


@pytest.fixture(scope="module")
def gf():
    from pixelkit.tech.technology import load_technology
    return load_technology("gf180mcu_3v3")


@pytest.fixture(scope="module")
def signed(tmp_path_factory, gf):
    """The structures through `pixelkit signoff` (LVS by labels, extraction): {structure: F}."""
    from pixelkit.layout.anylayout import signoff
    from pixelkit.layout.pex.structures import write
    folder = tmp_path_factory.mktemp("structures")
    gds, spice = write(gf, folder)
    r = signoff(gds, spice, gf, folder / "o", skip=("drc", "foundry-lvs", "lightmap"))
    assert r["lvs"]["match"] and r["pex"]["run"], r
    cpl = Couplings()
    for line in (folder / "o" / "STRUCTURES.caps.csv").read_text().splitlines()[1:]:
        a, b, c = line.split(",")
        cpl.add(a, b, float(c))
    return {st.name: term(cpl, st) for st in structures(gf)}


@pytest.fixture(scope="module")
def geo(tmp_path_factory, gf):
    from pixelkit.layout.pex.structures import geometry
    return geometry(gf, tmp_path_factory.mktemp("geo"))


@pytest.fixture(scope="module")
def other_sets(tmp_path_factory, gf):
    """{set: {structure: F}}: the development, validation and the seven holdout sets by the kit's model on
    FastCap2's windows."""
    from pixelkit.layout.pex.structures import geometry
    return {w: kit_terms(gf, geometry(gf, tmp_path_factory.mktemp(w), w), which=w) for w in REFS}


@pytest.mark.parametrize("name", HELD)
def test_structure_within_10_percent_of_fastcap_on_the_layered_stack(signed, name):
    assert signed[name] == pytest.approx(REF[name], rel=0.10, abs=0), f"{name}: {signed[name] / REF[name] - 1:+.1%}"


@pytest.mark.parametrize("which", sorted(REFS))
def test_development_validation_and_holdout_sets_against_fastcap(other_sets, which):
    """Every structure of the set within 10 % of FastCap2 but the documented misses, each held within 3
    points of the figure docs/post-layout.md gives (a change of the model that moves one is seen)."""
    kit, ref, misses = other_sets[which], REFS[which], KNOWN_MISSES[which]
    assert set(kit) == set(ref)
    err = {n: kit[n] / ref[n] - 1 for n in ref}
    bad = {n: f"{e:+.1%}" for n, e in err.items() if n not in misses and abs(e) > 0.10}
    moved = {n: f"{err[n]:+.1%} (documented {m:+.1%})" for n, m in misses.items()
             if not (abs(err[n]) > 0.10 and err[n] == pytest.approx(m, abs=0.03))}
    assert not bad and not moved, (bad, moved)


def test_post_layout_page_quotes_the_current_structure_terms(signed, other_sets):
    """docs/post-layout.md's structure tables quote the kit's term of each structure as computed above
    (``xs:SET.NAME`` marks: the first set through ``pixelkit signoff``, the others by the model on FastCap2's
    windows), FastCap2's from the stored reference (``file:``) and their difference (``calc:``): a change of
    the model that moves a quoted figure fails here, naming the line (``PIXELKIT_DOCS_REWRITE=1`` rewrites
    the figures; then read the sentences around them)."""
    import os
    from docsite import figures
    terms = {"first": signed, **other_sets}
    getters = {"xs": lambda key: terms[key.split(".")[0]][key.split(".", 1)[1]]}
    page = ROOT / "docs" / "post-layout.md"
    if os.environ.get("PIXELKIT_DOCS_REWRITE"):
        figures.update(None, [page], getters=getters)
    bad, n = figures.check(None, [page], getters=getters)
    assert n >= 366 and not bad, "\n".join(f"post-layout.md:{b['line']}: {b['key']}: quoted {b['quoted']}, now "
                                         f"{b.get('now') or b.get('why')}" for b in bad)


def test_post_layout_page_s_generated_structure_tables_are_the_kit_s(gf, signed, other_sets):
    """docs/post-layout.md's generated structure tables (``docsite/tables.py``: the holdout8 set) are what
    the model gives now on FastCap2's windows against the stored reference, row by row (the terms as
    structures.py draws them): a change of the model that moves a figure fails here."""
    from docsite import tables
    from pixelkit.layout.pex.structures import structures
    for which in ("holdout8",):
        data = {"terms": [(st.name, st.term) for st in structures(gf, which)], "kit": other_sets[which],
                "fastcap": REFS[which]}
        bad = tables.hold(which, data)
        assert not bad, bad
    kit = {"first": signed, **other_sets}
    sets = {w: {"terms": [(st.name, st.term) for st in structures(gf, w)], "kit": kit[w],
                "fastcap": REF if w == "first" else REFS[w]} for w in ("first", *REFS)}
    bad = tables.hold("structure-misses", sets)
    assert not bad, bad


def test_the_stack_gives_the_pdks_area_coefficients(gf):
    """The GF180MCU open PDK's extraction coefficients (Magic's tech file, as klayout-pex 0.6 carries them):
    metal1 over the substrate 29.304 aF/um2, metal2 over metal1 59.027, metal1 over poly 51.434. The layered
    stack gives them (the nitride liner raises metal1's by 1.8 % over a uniform k = 4: 28.79)."""
    st = gf.stack
    c = st.conductor
    m1_sub = st.eps_gap(0, c("metal1").z) / c("metal1").z * 1e6
    m2_m1 = st.eps_gap(c("metal1").top, c("metal2").z) / (c("metal2").z - c("metal1").top) * 1e6
    m1_poly = st.eps_gap(c("poly").top, c("metal1").z) / (c("metal1").z - c("poly").top) * 1e6
    assert m1_sub == pytest.approx(29.304, rel=1e-3, abs=0)
    assert m2_m1 == pytest.approx(59.027, rel=1e-3, abs=0)
    # the liner wraps the poly (0.05 um of k 7 over its top, in the 0.71 um to metal1): the stack lays it flat
    # over the field, below the poly's top, so metal1 over poly is 3.0 % under the PDK's (49.88 aF/um2)
    assert m1_poly == pytest.approx(51.434 * (0.66 / 4 + 0.05 / 7) / (0.71 / 4), rel=1e-3, abs=0)
    uniform = replace(st, dielectrics=())
    m1_sub_uniform = uniform.eps_gap(0, c("metal1").z) / c("metal1").z * 1e6
    assert m1_sub_uniform == pytest.approx(28.79, rel=1e-3, abs=0)
    # docs/post-layout.md quotes these (``stk:NAME`` marks, aF/um2)
    from docsite import figures
    now = {"m1_sub": m1_sub, "m2_m1": m2_m1, "m1_poly": m1_poly, "m1_sub_uniform": m1_sub_uniform}
    bad, n = figures.check(None, [ROOT / "docs" / "post-layout.md"], getters={"stk": now.__getitem__})
    assert n >= 4 and not bad, [(b["line"], b["key"], b["quoted"], b.get("now") or b.get("why")) for b in bad]


def _parallel_plate_only(mp):
    mp.setattr(capacitance, "fringe", lambda eps, t, h: 0.0)
    mp.setattr(capacitance.section, "pair", lambda *a: (0.0, 0.0, 0.0))
    mp.setattr(capacitance.section, "kept", lambda *a: (1.0, 1.0))
    mp.setattr(capacitance, "far_couplings", lambda *a: [])
    mp.setattr(capacitance, "corner_couplings", lambda *a: None)
    mp.setattr(capacitance, "wedge_couplings", lambda *a: None)
    mp.setattr(capacitance, "covered_top", lambda *a: [])


def _fringe_dropped(mp):
    mp.setattr(capacitance, "_fringe_band", lambda *a, **k: None)
    mp.setattr(capacitance, "covered_top", lambda *a: [])


WRONG = {"parallel plate only": (_parallel_plate_only, None), "fringe dropped": (_fringe_dropped, None),
         "half the metal thickness": (None, lambda st: replace(st, conductors=tuple(
             replace(c, thickness=c.thickness / 2) for c in st.conductors)))}


@pytest.mark.parametrize("wrong", list(WRONG))
def test_a_wrong_model_leaves_the_band_and_is_not_a_scaling(gf, geo, monkeypatch, wrong):
    """Each wrong model takes some structure outside 10 % of FastCap2, where the kit's model is inside it;
    and it moves the structures by different factors (a pure scaling, such as the dielectric taken as 2.0
    instead of 4.0, would move them all alike)."""
    patch, stack_of = WRONG[wrong]
    right = kit_terms(gf, geo)
    if patch:
        patch(monkeypatch)
    bad = kit_terms(gf, geo, stack_of(gf.stack) if stack_of else None)
    out = [n for n in HELD if abs(bad[n] / REF[n] - 1) > 0.10]
    assert out, {n: f"{bad[n] / REF[n] - 1:+.1%}" for n in HELD}
    assert all(abs(right[n] / REF[n] - 1) <= 0.10 for n in out)
    ratios = [bad[n] / right[n] for n in HELD if right[n] > 0]
    assert max(ratios) / max(min(ratios), 1e-9) > 1.10, ratios


def test_line_ends_raise_a_lines_ends_not_its_middle_nor_a_small_pad():
    """The far field's line ends (``farfield._line_ends``): a metal1 line 0.5 x 30 um keeps the 2.5D charge in
    its middle (its best-held edge piece) and gains towards its ends, where half its own potential is missing;
    a 0.5 um pad of the same net 10 um away is a polygon of its own, not the end of the line (unraised); no
    piece is lowered, and area pieces are left as they are."""
    import klayout.db as kdb
    import numpy as np
    from pixelkit.layout.pex import farfield
    dbu = 1e-9
    net = kdb.Region(kdb.Box(0, 0, 30000, 500)) + kdb.Region(kdb.Box(0, 10500, 500, 11000))
    pc = farfield._Pieces({"a": net}, ["a"], dbu, 1.23e-6, 0.55e-6, 4 * 8.854e-12 / 1.23e-6, 3e-11)
    pc.image = np.zeros(len(pc.x))
    q0 = pc.q.copy()
    farfield._line_ends(pc, 4 * 8.854e-12, 32e-6)
    k = pc.q / q0
    line = pc.edge & (pc.y < 1e-6) & (np.abs(pc.ny) > 0.5)          # the line's long edges
    mid = line & (np.abs(pc.x - 15e-6) < 1e-6)
    end = line & (pc.x < 0.5e-6)
    pad = pc.edge & (pc.y > 10e-6)
    assert np.all(k >= 1.0) and np.all(k[~pc.edge] == 1.0)
    assert k[mid].max() < 1.02 and k[end].min() > 1.15, (k[mid], k[end])
    assert k[pad].max() < 1.1, k[pad]


def test_floating_fill_is_reduced_as_a_schur_complement():
    """A floating conductor f between a and b (C_af = 2, C_bf = 3, C_f0 = 1 fF): eliminated, a and b gain
    2 x 3 / 6 = 1 fF between them, and their ground 2 x 1 / 6 and 3 x 1 / 6 (the node at V = sum C V / C_f)."""
    c = Couplings()
    c.add("a", "~metal1.0", 2e-15)
    c.add("b", "~metal1.0", 3e-15)
    c.add("0", "~metal1.0", 1e-15)
    c.add("a", "b", 0.5e-15)
    float_out(c)
    assert c.pair("a", "b") == pytest.approx(1.5e-15, rel=1e-12, abs=0)
    assert c.pair("a", "0") == pytest.approx(2e-15 / 6, rel=1e-12, abs=0)
    assert c.pair("b", "0") == pytest.approx(3e-15 / 6, rel=1e-12, abs=0)
    assert not any(n.startswith("~") for k in c.c for n in k)


@pytest.mark.slow
def test_the_stored_fastcap_reference_is_fastcaps(gf, tmp_path):
    """FastCap2 solved again (~2 min): the stored reference within 1 %."""
    from pixelkit.layout.pex.structures import fastcap_reference
    again = fastcap_reference(gf, tmp_path)
    assert all(again[n] == pytest.approx(REF[n], rel=0.01, abs=0) for n in REF), again


def test_pad_stacks_are_found_flush_and_an_overhang_is_not(gf, tmp_path, monkeypatch):
    """``stacks.Stacking`` on two metal1 - metal3 pad stacks (1 um, 1 um apart): each face's net continues
    flush on the layers under / over it (metal2's faces: one each way; their lateral section screened by the
    grouped 2D solve, < 1); a metal2 pad 0.5 um wider than the metal1 / metal3 under and over it is not
    flush (its faces stand alone: no screening, as before stacks were looked at)."""
    import numpy as np
    from pixelkit.layout.pex import structures as S
    from pixelkit.layout.pex.stacks import Stacking, screened

    def sets(tech):
        wide = [s for s in S._vias(tech, 10, 0, "ob", "metal3", 1.0) if s[0] != "metal2"]
        return [S._pads(tech, "p", "metal3", 1.0, 1.0, "p"),
                S.Structure("o", ("oa", "ob"), "overhang", tuple(
                    S._vias(tech, 7.5, 0, "oa", "metal3", 1.0) + wide + [("metal2", 9.5, -0.5, 11.5, 1.5, "ob")]))]
    monkeypatch.setitem(S.SETS, "stacks", sets)
    geo = S.geometry(gf, tmp_path, "stacks")
    st = Stacking(geo, gf.stack)
    m2 = next(k for k, c in enumerate(gf.stack.conductors) if c.name == "metal2")
    um = 1e-6 / geo.dbu
    mids = np.array([[1.0, 0.5], [2.0, 0.5], [88.5, 0.5], [89.5, 0.5]]) * um   # pa's, pb's, oa's, ob's faces (set pitch 80)
    normals = np.array([[1.0, 0], [-1.0, 0], [1.0, 0], [-1.0, 0]])
    down, up = st.runs(m2, ["pa", "pb", "oa", "ob"], mids, normals)
    assert down.tolist() == [1, 1, 1, 0] and up.tolist() == [1, 1, 1, 0]
    f = screened(gf.stack, m2, 1e-6, 1e-6, 1e-6, 1, 1)
    assert 0.5 < f < 0.9
    assert screened(gf.stack, m2, 1e-6, 1e-6, 1e-6, 0, 0) == 1.0
