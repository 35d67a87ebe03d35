"""designs/dual_pixel_revC.toml is what `pixelkit close` wrote from revA (docs/revisions.md): revA's file
with only the knobs its close.json reports moved, to the values it reports, and revA's specs kept. Its
sign-off (verify --mc-full, 13 min) is the dated record docs/records/revC_verify.json, not re-run here."""
import json
import tomllib

from conftest import ROOT

D = ROOT / "designs"


def _flat(table):
    """Dotted keys down to the values, a knob's entry ({choices} / {min, max}) kept whole: the design
    schema's own flattening of a [close] table."""
    from pixelkit.schema import _flat as flat
    return flat(table, {"choices", "min", "max"})


def test_revc_is_reva_with_the_knobs_close_reports_and_nothing_else():
    a = _flat(tomllib.loads((D / "dual_pixel_revA.toml").read_text()))
    c = _flat(tomllib.loads((D / "dual_pixel_revC.toml").read_text()))
    report = json.loads((D / "dual_pixel_revC.close.json").read_text())
    assert report["status"] == "closed" and report["source"] == "designs/dual_pixel_revA.toml"
    moved = {k for k in a.keys() | c.keys() if a.get(k) != c.get(k)}
    # the rename alone besides the knobs: revA's [close] table as shipped, the gate drive chosen by close
    allowed = set(report["overrides"]) | {"name", "revision"}
    assert moved <= allowed, sorted(moved - allowed)
    for key, value in report["overrides"].items():
        assert c[key] == value, key
    assert report["choose"] == "screen" and c["close.knobs.pixel.gate_drive"] == a["close.knobs.pixel.gate_drive"]


def test_revc_answers_to_reva_specs_and_its_record_passed():
    a, c = (tomllib.loads((D / f"dual_pixel_rev{r}.toml").read_text()) for r in "AC")
    assert a["spec"] == c["spec"]
    rec = json.loads((ROOT / "docs" / "records" / "revC_verify.json").read_text())
    assert rec["exit"] == 0 and rec["output"].count(" PASS ") == len(c["spec"]) and " FAIL " not in rec["output"]
