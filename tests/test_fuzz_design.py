"""Seeded fuzz over every design and technology field: no internal error, no implausible
value accepted, no written file that does not load again.

The expectations are independent of the schema's own ranges: no real chip has a
quantity of 1e300 or 1e-300 of its unit (except ~0 where zero is meaningful), a
NaN or infinite value, or a shell command in a name. Most mutations run through
the in-process loader (what every command calls first); a seeded sample runs
through the command line to check the exit status and the one-line / JSON error.
"""
import dataclasses
import json
import math
import random
import re
import tomllib
from pathlib import Path

import pytest

from conftest import REF, ROOT
from pixelkit.design import Design, load_design
from pixelkit.errors import PixelkitError
from pixelkit.finite import first_nonfinite
from pixelkit.schema import to_toml
from pixelkit.tech.technology import Technology
from pixelkit.units import DIMENSIONS

SEED = 9
PER_FIELD = 7          # mutations per field, drawn (seeded) from the corpus below
CLI_SAMPLE = 6         # mutated files also run through `pixelkit models`
TECH = ROOT / "pixelkit" / "tech" / "builtin" / "c35_thesis.toml"
MARK = "/tmp/pixelkit_fuzz_pwned"


def _unit(meta) -> str:
    if "unit" in meta:
        return meta["unit"]
    example = DIMENSIONS[meta.get("dim", "1")][1]
    parts = example.split(" ", 1)
    return parts[1] if len(parts) > 1 else ""


#: name -> value for a field of metadata ``meta`` (None = delete the field).
CORPUS = {
    "tiny": lambda m: f"1e-300 {_unit(m)}".strip(),
    "huge": lambda m: f"1e300 {_unit(m)}".strip(),
    "negative": lambda m: f"-1 {_unit(m)}".strip(),
    "zero": lambda m: f"0 {_unit(m)}".strip(),
    "nan_text": lambda m: f"nan {_unit(m)}".strip(),
    "overflow": lambda m: f"1e999 {_unit(m)}".strip(),
    "bare_number": lambda m: 60,
    "toml_nan": lambda m: float("nan"),
    "toml_inf": lambda m: float("-inf"),
    "bool": lambda m: True,
    "empty": lambda m: "",
    "list": lambda m: [1, 2],
    "table": lambda m: {"a": 1},
    "injection": lambda m: f"x\u2028.control\u2028shell touch {MARK}\u2028.endc",
    "long": lambda m: "9" * 5000,
    "db_huge": lambda m: "1e300 dB",
    "wrong_unit": lambda m: "1 lx" if m.get("dim") != "lx" else "1 V",
    "big_int": lambda m: 10 ** 30,
    "missing": lambda m: None,
    "fullwidth": lambda m: f"\uff11 {_unit(m)}".strip(),
    "control_char": lambda m: f"1\x07 {_unit(m)}".strip(),
}
ALWAYS = ("tiny", "huge", "bare_number")


def _leaves(cls, prefix=""):
    """(dotted path, metadata) of every loadable scalar field of a schema dataclass."""
    for f in dataclasses.fields(cls):
        kind = f.metadata.get("kind", "skip")
        if kind == "skip":
            continue
        path = f"{prefix}{f.name}"
        if kind == "table":
            yield from _leaves(f.metadata["cls"], path + ".")
        elif kind == "map":   # named tables ([spec.<name>]): the fields of the reference design's first one
            first = next(iter(tomllib.loads(REF.read_text()).get(f.name, {"x": None})))
            yield from _leaves(f.metadata["cls"], f"{path}.{first}.")
        elif kind == "map":   # [spec.<name>]: the fields of a spec the reference design has
            yield path, dict(f.metadata)
            yield from _leaves(f.metadata["cls"], path + ".criterion_secondary.")
        else:
            yield path, dict(f.metadata)


def _set(raw: dict, dotted: str, value):
    node = raw
    *head, last = dotted.split(".")
    for part in head:
        node = node.setdefault(part, {})
    if value is None:
        node.pop(last, None)
    else:
        node[last] = value


def _tech_raw() -> dict:
    from pixelkit.tech import load_technology
    raw = tomllib.loads(TECH.read_text())
    raw["models"]["folder"] = str(load_technology("c35_thesis").models.folder)
    return raw


def _cases():
    rng = random.Random(SEED)
    fields = [("design", p, m) for p, m in _leaves(Design)]
    fields += [("tech", p, m) for p, m in _leaves(Technology)]
    fields += [("tech", "models.folder", {"kind": "str"}), ("tech", "models.default_corner", {"kind": "ident"}),
               ("tech", "photodiode.qe_curve", {"kind": "list"})]
    # issue 44: the foundry rules the generators draw with (a seeded sample of the 84) and the deck keys
    rules = _rule_fields()
    fields += [("tech", p, m) for p, m in rng.sample(rules, RULE_SAMPLE)]
    fields += [("tech", f"signoff.{k}", {"kind": "str"}) for k in ("drc_deck", "drc_sha256", "lvs_deck", "lvs_sha256")]
    fields = [(w, p, _spec_unit(p, m)) for w, p, m in fields]
    for where, path, meta in fields:
        names = list(ALWAYS) + rng.sample([n for n in CORPUS if n not in ALWAYS], PER_FIELD - len(ALWAYS))
        for name in names:
            yield where, path, meta, name


RULE_SAMPLE = 12


def _rule_fields():
    """(dotted path, metadata) of every per-layer rule of the technology ([rules.<layer>])."""
    out = []
    for layer, table in tomllib.loads(TECH.read_text())["rules"].items():
        if not isinstance(table, dict):
            continue
        for kind, v in table.items():
            dim = "m2" if kind == "area" else "m"
            for path in ([f"rules.{layer}.{kind}.{o}" for o in v] if kind in ("enclosure", "extension", "space_to")
                         else [f"rules.{layer}.{kind}"]):
                out.append((path, {"kind": "rule", "dim": dim, "pair": kind in ("enclosure", "extension", "space_to")}))
    return out


def _spec_unit(path: str, meta: dict) -> dict:
    """A spec limit is fuzzed in its figure's unit (the reference's first spec: a conversion gain), a
    [close] knob's bound in its key's (the base knob below: pixel.sf_bias, a current)."""
    if path.startswith("spec.") and meta.get("kind") == "limit":
        from pixelkit.verify.figures import FIGURES
        return {**meta, "unit": FIGURES[path.split(".")[1]].unit}
    if path.startswith("close.knobs.") and meta.get("kind") == "limit":
        return {**meta, "unit": "nA"}
    return meta


#: issue 44, point 7: [close] (issue 40) is fuzzed on a valid table, one knob, each field mutated in turn
CLOSE_BASE = {"objective": "min power", "knobs": {"pixel.sf_bias": {"min": "600 nA", "max": "1.5 uA"}}}


def _write_case(tmp: Path, k: int, where, path, meta, name) -> Path:
    value = CORPUS[name](meta)
    design = tomllib.loads(REF.read_text())
    if where == "design" and path.startswith("close."):
        design["close"] = json.loads(json.dumps(CLOSE_BASE))
        if path.startswith("close.knobs."):
            _set(design["close"]["knobs"]["pixel.sf_bias"], path.rsplit(".", 1)[1], value)
        else:
            _set(design, path, value)
    elif where == "design":
        _set(design, path, value)
    else:
        tech = _tech_raw()
        _set(tech, path, value)
        (tmp / f"t{k}.toml").write_text(to_toml(tech))
        design["technology"] = str(tmp / f"t{k}.toml")
    out = tmp / f"d{k}.toml"
    out.write_text(to_toml(design))
    return out


def _must_refuse(name: str, meta: dict) -> bool:
    """Independent expectation: values no real chip, lens or scene has."""
    qty = meta.get("kind") == "qty"
    if name in ("huge", "nan_text", "overflow", "toml_nan", "toml_inf", "db_huge") and qty:
        return True
    if name == "tiny" and qty and meta.get("ge") is None and meta.get("dim") != "K":
        return True  # 1e-300 of a unit is only meaningful as "zero", where zero is allowed (1e-300 degC is 0 degC)
    if name == "injection" and meta.get("kind") in ("ident", "qty", "int", "bool"):
        return True
    if meta.get("kind") in ("limit", "rule"):   # issue 44: a spec limit / a design rule no chip has
        if name in ("huge", "tiny", "negative", "nan_text", "overflow", "toml_nan", "toml_inf", "db_huge", "big_int",
                    "list", "table", "injection", "long", "wrong_unit", "control_char"):
            return True
        return name == "zero" and not meta.get("pair")
    return name in ("big_int", "list", "table") and meta.get("kind") in ("qty", "int", "ident", "bool")


def test_fuzz_every_field(tmp_path):
    from pixelkit.optimize.flow import sized_design_text
    from pixelkit.api import models as model_table   # the physics table at the SPICE SF gain
    problems, n_loaded, n_refused, files = [], 0, 0, []
    other = tmp_path / "elsewhere" / "deeper"
    other.mkdir(parents=True)
    sized = {"mask_open_m2": 0.64e-12, "t_int_primary_s": 1e-3, "t_int_secondary_s": 12e-3, "level": "analytic",
             "c_m": 39.0}
    for k, (where, path, meta, name) in enumerate(_cases()):
        label = f"{where}:{path}={name}"
        f = _write_case(tmp_path, k, where, path, meta, name)
        files.append((label, f))
        try:
            d = load_design(f)
        except PixelkitError as exc:
            n_refused += 1
            if "\n" in str(exc) or "\u2028" in str(exc):
                problems.append(f"{label}: error is not one line: {str(exc)[:200]!r}")
            continue
        except Exception as exc:  # noqa: BLE001 - an internal error is what the fuzz looks for
            problems.append(f"{label}: internal error {type(exc).__name__}: {exc}"[:300])
            continue
        n_loaded += 1
        if _must_refuse(name, meta):
            problems.append(f"{label}: accepted a value no chip has")
        try:
            hit = first_nonfinite(model_table(d))
        except PixelkitError:
            hit = None
        except Exception as exc:  # noqa: BLE001
            problems.append(f"{label}: model table internal error {type(exc).__name__}: {exc}"[:300])
            continue
        if hit:
            problems.append(f"{label}: loaded, but the model table holds {hit}")
        written = other / f"{d.name}_{k}_sized.toml"
        written.write_text(sized_design_text(d, sized, written))
        try:
            again = load_design(written)
            assert again.revision == d.revision and again.name.endswith("_sized")
        except Exception as exc:  # noqa: BLE001
            problems.append(f"{label}: the sized design written from it does not load: {exc}"[:300])
    assert not Path(MARK).exists()
    assert not problems, "\n".join(problems[:40])
    assert n_refused > n_loaded > 0  # the corpus is mostly hostile, and some of it is harmless

    rng = random.Random(SEED)
    from conftest import run_cli
    for label, f in rng.sample(files, CLI_SAMPLE):
        code, out, err = run_cli("models", f, "--json", timeout=120)
        assert code in (0, 2), (label, code, err)
        obj = json.loads(out, parse_constant=lambda c: pytest.fail(f"{label}: {c} in JSON"))
        assert ("error" in obj) == (code == 2), label
        code2, out2, err2 = run_cli("models", f, timeout=120)
        assert code2 == code and (code == 0 or len(err2.strip().splitlines()) == 1), (label, err2)


@pytest.mark.parametrize("make,ok", [
    (lambda p: p.write_bytes(b"\xef\xbb\xbf" + REF.read_bytes()), True),          # a BOM is fine
    (lambda p: p.write_bytes(REF.read_bytes().replace(b'"A"', b'"\xff\xfe"')), False),  # not UTF-8
    (lambda p: p.write_text("x = " + "[" * 5000 + "]" * 5000 + "\n"), False),    # 5000-deep
    (lambda p: p.write_bytes(b""), False),
    (lambda p: p.write_bytes(bytes(range(256)) * 4), False),                       # binary
    (lambda p: p.mkdir(), False),                                                  # a folder
    (lambda p: p.write_text(REF.read_text().replace('"60 dB"', "60")), False),     # ambiguous gain
    (lambda p: p.write_text(REF.read_text().replace('"60 dB"', '"1000 V/V"')), True),
    (lambda p: p.write_text(REF.read_text().replace('"200 fF"', '"1e300 fF"')), False),
    (lambda p: p.write_text(REF.read_text().replace('"60 dB"', '"1e300 dB"')), False),
], ids=["bom", "latin1", "deep", "empty", "binary", "folder", "gain60", "gainVV", "column_cap", "dB"])
def test_whole_file_faults_are_one_line(tmp_path, make, ok):
    p = tmp_path / "d.toml"
    make(p)
    if ok:
        assert load_design(p).afe.gain == pytest.approx(1000.0)
        return
    with pytest.raises(PixelkitError) as e:
        load_design(p)
    assert "\n" not in str(e.value) and str(p) in str(e.value)


def test_errors_echo_values_as_written(tmp_path):
    p = tmp_path / "d.toml"
    p.write_text(REF.read_text().replace('swing = "1.5 V"', 'swing = "1e-300 V"'))
    with pytest.raises(PixelkitError) as e:
        load_design(p)
    assert "pixel.swing = '1e-300 V'" in str(e.value) and "50 mV" in str(e.value)
    p.write_text(REF.read_text().replace('"60 dB"', "60"))
    with pytest.raises(PixelkitError) as e:
        load_design(p)
    assert "afe.gain = 60" in str(e.value) and "ambiguous" in str(e.value)


def _tech_variant(tmp_path, **edits):
    raw = _tech_raw()
    for dotted, v in edits.items():
        _set(raw, dotted.replace("__", "."), v)
    (tmp_path / "t.toml").write_text(to_toml(raw))
    d = tmp_path / "d.toml"
    d.write_text(REF.read_text().replace('"c35_thesis"', json.dumps(str(tmp_path / "t.toml"))))
    return d


def test_two_layers_on_one_gds_layer_are_refused_at_load(tmp_path):
    with pytest.raises(PixelkitError) as e:
        load_design(_tech_variant(tmp_path, layers__shield={"layer": 21, "datatype": 0}))  # the PD's n-well
    assert "distinct_layers" in str(e.value)


def test_a_grid_that_cannot_draw_the_opening_is_a_layout_error(tmp_path, cli):
    """A 1 um grid draws the 0.64 um2 opening as 1 um2: `layout` refuses with the rule; the
    circuit commands run the design with that warning."""
    p = _tech_variant(tmp_path, rules__grid="1 um")
    code, out, err = cli("layout", p, "--out", tmp_path / "o")
    assert code == 2 and "grid_resolves_opening" in err and len(err.strip().splitlines()) == 1
    code, out, err = cli("models", p)
    assert code == 0 and "grid_resolves_opening" in err


def test_pd_that_leaves_no_room_for_transistors_is_a_layout_error(tmp_path, cli):
    """A 6 x 6 um PD in the 8 um secondary cell: the transistors do not fit beside it (the
    generator's rule). `layout` refuses it naming the PD (not the pitch, not a transistor: the
    devices would fit beside a PD of the technology's smallest side); `models` runs it with a
    warning, so a designer can ask "what if"."""
    p = tmp_path / "d.toml"
    p.write_text(re.sub(r'^pd_width = "5 um"\npd_height = "5 um"', 'pd_width = "6 um"\npd_height = "6 um"',
                        REF.read_text(), flags=re.M))
    code, out, err = cli("layout", p, "--out", tmp_path / "o")
    assert code == 2 and "transistors_fit" in err and "secondary.pd_width" in err
    assert len(err.strip().splitlines()) == 1
    code, out, err = cli("models", p)
    assert code == 0 and "transistors_fit" in err and "warning" in err


def test_size_writer_output_loads_again_from_another_folder(tmp_path):
    """A control character in `revision`, a 64-character name, a relative technology path:
    the sized design, written into another folder, loads again with the same values."""
    from pixelkit.optimize.flow import sized_design_text
    src = tmp_path / "src"
    src.mkdir()
    (src / "tech.toml").write_text(to_toml(_tech_raw()))
    raw = tomllib.loads(REF.read_text())
    raw.update(name="n" * 64, revision="A\x07\"B\\\u2028", technology="tech.toml")
    (src / "d.toml").write_text(to_toml(raw))
    d = load_design(src / "d.toml")
    out = tmp_path / "out" / "sized.toml"
    out.parent.mkdir()
    sized = {"mask_open_m2": 0.81e-12, "t_int_primary_s": 2e-3, "t_int_secondary_s": 20e-3, "level": "spice",
             "c_m": 30.9}
    out.write_text(sized_design_text(d, sized, out))
    again = load_design(out)
    assert again.revision == raw["revision"] and len(again.name) <= 64 and again.name.endswith("_sized")
    assert Path(again.tech.source).resolve() == (src / "tech.toml").resolve()
    assert again.secondary.mask_opening == pytest.approx(0.81e-12) and again.primary.t_int == pytest.approx(2e-3)


def test_measured_swing_too_small_stops_the_figures(ref_design):
    from pixelkit.experiments.thesis import _check_swing
    with pytest.raises(PixelkitError) as e:
        _check_swing(ref_design, 1.7e-23, 0.5)
    assert "primary swing" in str(e.value) and "not computed" in str(e.value)
    _check_swing(ref_design, 0.9, 0.9)


def test_nonfinite_figures_are_not_printed():
    from pixelkit.finite import refuse_nonfinite
    with pytest.raises(PixelkitError) as e:
        refuse_nonfinite({"primary": {"fwc_e": math.inf}})
    assert "primary.fwc_e" in str(e.value)
    refuse_nonfinite({"a": [1.0, 2.0], "b": "x"})


def test_report_section_lists_values_near_a_range_edge(tmp_path):
    """A 4.9 V swing (plausible up to 5 V) with a 5 V supply is listed first as near the edge;
    a 1.5 V swing is not."""
    from pixelkit.report.sections import inputs

    class Ctx:
        pass
    ctx = Ctx()
    ctx.design = load_design(REF)
    assert "design: pixel.swing" not in inputs.build(ctx).data["near_edge"]
    tech = _tech_raw()
    tech["supply"] = "5 V"
    (tmp_path / "t.toml").write_text(to_toml(tech))
    p = tmp_path / "d.toml"
    p.write_text(REF.read_text().replace('"c35_thesis"', json.dumps(str(tmp_path / "t.toml")))
                 .replace('swing = "1.5 V"', 'swing = "4.9 V"').replace('"2.0 V"', '"4.95 V"'))
    ctx.design = load_design(p)
    s = inputs.build(ctx)
    assert "design: pixel.swing" in s.data["near_edge"]
    assert s.tables[0].rows[0][5] == "near the edge"


def test_fuzz_timing_tables(tmp_path):
    """Seeded random [primary.timing] / [secondary.timing] tables and read clocks: each design
    either loads, and then its phases are in order with room for their edges and both decks
    write strictly increasing waveforms, or is refused naming a timing key (or the clock or
    exposure it does not fit) in one line. The order rule is written here, independently of
    the loader's."""
    from pixelkit.circuits.array import array_bench
    from pixelkit.circuits.testbench import dual_pixel_bench, timings
    from pixelkit.readout_timing import ROW_FRACTIONS
    rng = random.Random(SEED)
    order = [k for k, _ in ROW_FRACTIONS]
    loaded = refused = 0
    for k in range(160):
        raw = tomllib.loads(REF.read_text())
        kind = rng.choice(["primary", "secondary"])
        f_read = rng.choice([1e5, 5e5, 1e6, 2e6, 1e7])
        raw[kind]["f_read"] = f"{f_read:g} Hz"
        t_row = 1 / f_read
        table = {}
        for key in rng.sample(order, rng.randint(0, len(order))):
            table[key] = f"{rng.uniform(0, 1.1) * t_row * 1e6:.4g} us"
        for key in rng.sample(["t_reset", "t_tg", "t_gap", "t_pre", "edge", "t_hold"], rng.randint(0, 3)):
            table[key] = f"{10 ** rng.uniform(-9, -5):.3g} s"
        raw[kind]["timing"] = table
        p = tmp_path / f"t{k}.toml"
        p.write_text(to_toml(raw))
        try:
            d = load_design(p)
        except PixelkitError as exc:
            refused += 1
            assert "\n" not in str(exc)
            assert exc.field.startswith(f"{kind}.timing.") or exc.field in ("experiment.t_window", f"{kind}.t_int"), \
                (table, str(exc))
            continue
        loaded += 1
        t = timings(d, d.experiment.t_window, 2)[kind]
        edge = t.edge
        ph = [t.phase(n) for n in order]
        assert all(0 <= x <= t.t_row for x in ph), (table, ph)
        for (a, b), (na, nb) in zip(zip(ph, ph[1:]), zip(order, order[1:])):
            assert b - a >= (0 if na == "rs_on" else edge), (table, na, nb, a, b)
        assert t.phase("rs_off") + edge <= t.t_row + t.phase("rs_on") * (1 + 1e-12), table
        dual_pixel_bench(d, 1e-9, 1e-11, with_afe=True).text()
        ip = [[1e-9]]
        array_bench(d, ip, [[1e-11] * d.secondary_per_pixel], t_exp=None, with_afe=True).text()
    assert loaded > 10 and refused > 10, (loaded, refused)
