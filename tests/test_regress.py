import json
import re

from conftest import REF


def test_regress_passes_unchanged_and_fails_on_a_device_change(tmp_path, cli):
    base = tmp_path / "baseline.json"
    code, out, err = cli("regress", REF, "--baseline", base, "--update")
    assert code == 0, err
    code, out, err = cli("regress", REF, "--baseline", base, "--json")
    assert code == 0, err
    assert json.loads(out)["changed"] == []
    changed = tmp_path / "d.toml"
    # a narrower SF (a wider one no longer fits the 8 um secondary cell: layout rule transistors_fit)
    changed.write_text(re.sub(r'^sf_w = "1 um"', 'sf_w = "0.6 um"', REF.read_text(), flags=re.M))
    code, out, err = cli("regress", changed, "--baseline", base)
    assert code == 1, err
    assert "CHANGED" in out


def test_regress_missing_baseline_is_a_clear_error(tmp_path, cli):
    code, out, err = cli("regress", REF, "--baseline", tmp_path / "none.json")
    assert code == 2 and "--update" in err and "Traceback" not in err
