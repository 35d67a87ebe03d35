"""Layout: GDS generation, KLayout read-back, extraction, rules, golden geometry."""
import json
import re
from dataclasses import replace
from pathlib import Path

import gdstk
import pytest

from conftest import REF, ROOT
from pixelkit.design import with_layout
from pixelkit.layout.cells import build_library, opening_side
from pixelkit.layout.compare import identical, xor_report
from pixelkit.layout.extract import extract
from pixelkit.layout.flow import write_gds
from pixelkit.layout.rules import RuleError


@pytest.fixture(scope="module")
def gds(tmp_path_factory, ref_design):
    return write_gds(build_library(ref_design, 2, 2), tmp_path_factory.mktemp("gds") / "ref.gds")


def test_extracted_geometry_equals_drawn(gds, ref_design):
    ex = extract(gds, ref_design.tech)
    for which in ("primary", "secondary"):
        sub = getattr(ref_design, which)
        assert ex[which]["pd_area_m2"] == pytest.approx(sub.pd_width * sub.pd_height, rel=1e-9)
        assert ex[which]["pd_perimeter_m"] == pytest.approx(2 * (sub.pd_width + sub.pd_height), rel=1e-9)
    # C_A = 8.18 ([Thesis2019] eq. 3.10) within 1 %
    assert ex["primary"]["pd_area_m2"] / ex["secondary"]["pd_area_m2"] == pytest.approx(8.18, rel=0.01)
    # the unmasked primary collects over its whole PD; the masked secondary over the opening only
    assert ex["primary"]["photoactive_area_m2"] == pytest.approx(ex["primary"]["pd_area_m2"], rel=1e-9)
    side = opening_side(ref_design.secondary.mask_opening, ref_design.tech.rules.grid * 1e6) * 1e-6
    assert ex["secondary"]["photoactive_area_m2"] == pytest.approx(side ** 2, rel=1e-9)
    assert ex["secondary"]["photoactive_area_m2"] == pytest.approx(ref_design.secondary.mask_opening, rel=0.01)


def test_klayout_reads_cells_layers_and_references(gds, ref_design):
    import klayout.db as kdb
    ly = kdb.Layout()
    ly.read(str(gds))
    cells = {c.name: c for c in ly.each_cell()}
    assert set(cells) == {"PRIMARY", "SECONDARY", "DUALPIX", "ARRAY_2X2"}
    layers = {(i.layer, i.datatype) for i in ly.layer_infos()}
    t = ref_design.tech.layers
    for name in ("pd", "active", "poly", "contact", "metal1", "shield", "opening", "boundary"):
        assert (getattr(t, name).layer, getattr(t, name).datatype) in layers, name
    dual = [(ly.cell(i.cell_index).name, i.na * i.nb if i.is_regular_array() else 1)
            for i in cells["DUALPIX"].each_inst()]
    assert sorted(dual) == [("PRIMARY", 1), ("SECONDARY", ref_design.secondary_per_pixel)]
    arr = list(cells["ARRAY_2X2"].each_inst())
    assert len(arr) == 1 and arr[0].is_regular_array() and (arr[0].na, arr[0].nb) == (2, 2)
    # by reference: the array cell holds no polygons of its own
    assert cells["ARRAY_2X2"].shapes(ly.layer(t.pd.layer, t.pd.datatype)).size() == 0


def test_full_chip_array_is_built_by_reference(tmp_path, ref_design):
    small = write_gds(build_library(ref_design, 2, 2), tmp_path / "a.gds").stat().st_size
    big = write_gds(build_library(ref_design, 27, 50), tmp_path / "b.gds").stat().st_size
    assert big - small < 200


def test_geometry_matches_golden(ref_design):
    golden = gdstk.read_gds(str(ROOT / "layouts" / "golden" / f"{ref_design.name}.gds"))
    report = xor_report(golden, build_library(ref_design, 2, 2))
    assert identical(report), f"layout changed: {report}; review, then `python -m pixelkit layout " \
                              f"designs/dual_pixel_revA.toml --golden`"


def test_xor_catches_a_changed_opening(ref_design):
    golden = gdstk.read_gds(str(ROOT / "layouts" / "golden" / f"{ref_design.name}.gds"))
    d = replace(ref_design, secondary=replace(ref_design.secondary, mask_opening=0.81e-12))
    report = xor_report(golden, build_library(d, 2, 2))
    assert not identical(report) and "SECONDARY" in report["diff"]


@pytest.mark.parametrize("changes,rule", [
    ({"mask_opening": 0.2e-12}, "min_opening_side"),
    ({"mask_opening": 20e-12}, "opening_to_pd_edge"),
    ({"pd_width": 7.5e-6}, "pd_to_cell_edge"),
    ({"pd_width": 4e-6}, "min_pd_side"),
])
def test_rules_refuse_with_the_rule_named(ref_design, changes, rule):
    d = replace(ref_design, secondary=replace(ref_design.secondary, **changes))
    with pytest.raises(RuleError) as e:
        build_library(d)
    assert e.value.rule == rule and "SECONDARY" in str(e.value)


def test_models_and_netlists_use_the_extracted_geometry(tmp_path, ref_design):
    from pixelkit.circuits.pixel5t import pixel5t
    from pixelkit.api import models as model_table
    drawn = replace(ref_design, secondary=replace(ref_design.secondary, pd_width=5.1e-6, pd_height=5.1e-6))
    gds = write_gds(build_library(drawn), tmp_path / "six.gds")
    d = with_layout(ref_design, gds)          # the design says 5 x 5 um; the layout says 5.1 x 5.1 um
    assert model_table(d)["c_a"] == pytest.approx(204.605 / 26.01, rel=1e-6)
    text = pixel5t(d, "secondary").text()
    assert "area=2.601e-11" in text and "pj=2.04e-05" in text


def test_layout_cli_json(tmp_path, cli):
    code, out, err = cli("layout", REF, "--json", "--out", tmp_path)
    assert code == 0, err
    r = json.loads(out)
    assert Path(r["gds"]).exists() and r["c_a"] == pytest.approx(8.18, rel=0.01)
    for which in ("primary", "secondary"):
        assert {"pd_area_m2", "pd_perimeter_m", "photoactive_area_m2"} <= set(r[which])
    for png in (r["png"], r["png_3d"]):
        assert Path(png).read_bytes()[:4] == b"\x89PNG" and Path(png).stat().st_size > 5000


def test_layout_cli_rule_error_is_one_line(tmp_path, cli):
    bad = tmp_path / "d.toml"
    bad.write_text(re.sub(r'^mask_opening = "0.64 um2"', 'mask_opening = "0.1 um2"', REF.read_text(), flags=re.M))
    code, out, err = cli("layout", bad, "--out", tmp_path)
    assert code == 2 and "min_opening_side" in err and "SECONDARY" in err and "Traceback" not in err
    assert not list(tmp_path.glob("*.gds"))


def test_pd_larger_than_its_cell_is_refused_with_the_rule(tmp_path, cli):
    bad = tmp_path / "d.toml"
    bad.write_text(re.sub(r'^pd_width = "5 um"', 'pd_width = "9 um"', REF.read_text(), flags=re.M))
    code, out, err = cli("layout", bad, "--out", tmp_path)
    assert code == 2 and "pd_to_cell_edge" in err and "secondary.pd_width" in err and "Traceback" not in err
