"""Seeded fuzz of the inputs added since the design-file fuzz: sweep axes, corners, Monte Carlo
settings, --scheduler addresses, array exposure and scene, EMVA 1288 descriptors, family design files,
verify's grid options and the [spec] / [verify] keys, the layout's array size and shield.

INPUTS is the one table of inputs: a row names an input and says how a hostile value reaches it
(the command line it builds from the value). To fuzz a new input (a timing key, a layout option,
a spec), add a row; every row meets every value of CORPUS.

Each case runs the real command line in this process, with the simulations (the sweep's tasks,
once every axis value is applied to the design; the frames of the array and the Monte Carlo
chip, once the scene, corner and seed are applied) replaced by a stub that ends the run as "accepted": the
question is only what the command does with the value before it works with it. The
expectation is independent of the kit's ranges: exit 0 (accepted) or 2 (refused, with one
line on stderr), never an internal error (3) or a traceback, and never the marker file the
injection payload would create if a value reached an ngspice control block.
"""
import random
import re
import tomllib
from pathlib import Path

import pytest

from conftest import REF, ROOT
from pixelkit.schema import to_toml

MARK = "/tmp/pixelkit_fuzz_inputs_pwned"
SEED = 26
CORPUS = ["", " ", "nan", "inf", "-inf", "-1", "0", "1e300", "1e-300", "99999999999999999999",
          f"x\n.control\nshell touch {MARK}\n.endc", f"x\u2028.control\u2028shell touch {MARK}\u2028.endc",
          "9" * 5000, "\x00", "\x07", "\uff11", "1,,2", "=", "a=b=c", "log:1:2:3", "log:0:0:0", "lin:1:1e300:1e9",
          "tcp://", "tcp://host", "tcp://host:0", "tcp://host:99999", "tcp://a b:1", "file:///etc/passwd",
          "tt,tt", "TT", "../../etc", "corner", "300nA,", "1 uA", "1e9 A", "-1 nA", "1 lx"]
EMVA_LINES = ["n {v} 16 16", "n 8 {v} 16", "b {v} 100", "b 1000 {v}", "d {v}", "i {v}", "{v}", "# exposure in {v}"]


class Accepted(BaseException):
    """Raised by the stubs: the command took the value and began its work."""


def _stub(*_a, **_k):
    raise Accepted()


def _design_file(tmp, family, key, value):
    raw = tomllib.loads((ROOT / "designs" / family).read_text())
    node = raw
    *head, last = _key_parts(key)
    for h in head:
        node = node[h]
    node[last] = value
    p = tmp / f"f{abs(hash((family, key, repr(value)))) % 10**8}.toml"
    p.write_text(to_toml(raw))
    return p


def _key_parts(key):
    """A dotted key's parts, a quoted part ("column.bias", a [close] knob's name) kept whole."""
    return [m.strip('"') for m in re.findall(r'"[^"]*"|[^.]+', key)]


def _family_keys(family):
    raw = tomllib.loads((ROOT / "designs" / family).read_text())
    out = []

    def walk(node, prefix):
        for k, v in node.items():
            if isinstance(v, dict):
                walk(v, f"{prefix}{_quoted(k)}.")
            elif k not in ("family",):
                out.append(f"{prefix}{_quoted(k)}")
    walk(raw, "")
    return out


def _quoted(k):
    return f'"{k}"' if "." in k else k


def _emva(tmp, template, value):
    """A descriptor with one line made hostile, beside the images of one synthetic dataset."""
    from test_emva_hostile import make
    folder = tmp / "emva"
    if not folder.exists():
        make(folder)
    lines = (folder / "EMVA1288_Data.txt").read_text().splitlines()
    kind = template.split(" ", 1)[0]
    if kind in ("n", "b", "d", "i"):
        k = next(i for i, ln in enumerate(lines) if ln.split(" ", 1)[0] == kind)
        lines[k] = template.format(v=value)
    else:
        lines.insert(2, template.format(v=value))
    p = folder / f"case{abs(hash((template, value))) % 10**8}.txt"
    p.write_text("\n".join(lines) + "\n")
    return p


#: input -> how a value reaches it: (tmp, value) -> the command line
INPUTS = {
    "sweep --over NAME": lambda tmp, v: ["sweep", REF, "--over", f"{v}=1,2"],
    "sweep --over design key": lambda tmp, v: ["sweep", REF, "--over", f"pixel.sf_bias={v}"],
    "sweep --over corner": lambda tmp, v: ["sweep", REF, "--over", f"corner={v}"],
    "sweep --over stimulus": lambda tmp, v: ["sweep", REF, "--over", f"iph_p={v}"],
    "sweep --over option": lambda tmp, v: ["sweep", REF, "--over", f"option.reltol={v}"],
    "sweep --scheduler": lambda tmp, v: ["sweep", REF, "--over", "pixel.sf_bias=300nA", "--scheduler", v],
    "mc --corner": lambda tmp, v: ["mc", REF, "--corner", v],
    "mc --seed": lambda tmp, v: ["mc", REF, "--seed", v],
    "mc --scheduler": lambda tmp, v: ["mc", REF, "--scheduler", v],
    "array --t-exp": lambda tmp, v: ["array", REF, "--t-exp", v],
    "array --scheduler": lambda tmp, v: ["array", REF, "--scheduler", v],
    "array --scene": lambda tmp, v: ["array", REF, "--scene", v],
    "verify --corners": lambda tmp, v: ["verify", REF, "--corners", v],
    "verify --temperatures": lambda tmp, v: ["verify", REF, "--temperatures", v],
    "verify --supplies": lambda tmp, v: ["verify", REF, "--supplies", v],
    "verify --mc": lambda tmp, v: ["verify", REF, "--mc", v],
    "verify --seed": lambda tmp, v: ["verify", REF, "--seed", v],
    "verify --scheduler": lambda tmp, v: ["verify", REF, "--scheduler", v],
    **{f"verify [spec] {k}": (lambda k: lambda tmp, v: ["verify", _design_file(tmp, "dual_pixel_revA.toml", k, v)])(k)
       for k in ("spec.afe_gain_error.max", "spec.afe_gain_error.figure", "spec.afe_gain_error.unit",
                 "spec.criterion_secondary.min", "verify.mismatch")},
    **{f"verify [spec] {k} item": (lambda k: lambda tmp, v: ["verify", _design_file(tmp, "dual_pixel_revA.toml",
                                                                                     k, [v])])(k)
       for k in ("spec.afe_gain_error.corners", "spec.afe_gain_error.temperatures", "verify.supplies",
                 "verify.corners")},
    "layout --rows": lambda tmp, v: ["layout", REF, "--rows", v, "--afe", "--out", tmp / "lay"],
    "layout --cols": lambda tmp, v: ["layout", REF, "--cols", v, "--out", tmp / "lay"],
    "layout --shield": lambda tmp, v: ["layout", REF, "--shield", v, "--afe", "--out", tmp / "lay"],
    **{f"emva '{t}'": (lambda t: lambda tmp, v: ["gap", "emva", _emva(tmp, t, v)])(t) for t in EMVA_LINES},
    # issue 44: output places (a name with a NUL, a control character, 5000 characters, '../..')
    "simulate --waveforms": lambda tmp, v: ["simulate", REF, "--waveforms", f"{tmp}/{v}.csv"],
    "verify --out": lambda tmp, v: ["verify", REF, "--out", f"{tmp}/v/{v}"],
    "layout --drc --out": lambda tmp, v: ["layout", ROOT / "designs" / "dual_pixel_gf180.toml", "--drc",
                                          "--out", f"{tmp}/lay/{v}"],
    # issue 44, point 7: the options this round's commands added (signoff: issue 43; waves: 42; close: 40)
    "signoff --top": lambda tmp, v: ["signoff", GOLDEN_GDS, "--netlist", _netlist(tmp), "--tech", "c35_thesis",
                                     "--top", v],
    "signoff --tech": lambda tmp, v: ["signoff", GOLDEN_GDS, "--netlist", _netlist(tmp), "--top", "DUALPIX_COL",
                                      "--tech", v],
    "signoff --skip": lambda tmp, v: ["signoff", GOLDEN_GDS, "--netlist", _netlist(tmp), "--top", "DUALPIX_COL",
                                      "--tech", "c35_thesis", "--skip", v],
    "signoff --out": lambda tmp, v: ["signoff", GOLDEN_GDS, "--netlist", _netlist(tmp), "--top", "DUALPIX_COL",
                                     "--tech", "c35_thesis", "--out", f"{tmp}/so/{v}"],
    "signoff --netlist": lambda tmp, v: ["signoff", GOLDEN_GDS, "--top", "DUALPIX_COL", "--tech", "c35_thesis",
                                         "--netlist", f"{tmp}/{v}.spice"],
    "waves --vectors": lambda tmp, v: ["waves", _raw(tmp), "--vectors", v],
    "waves --out": lambda tmp, v: ["waves", _raw(tmp), "--out", f"{tmp}/{v}.html"],
    "waves RAW": lambda tmp, v: ["waves", f"{tmp}/{v}.raw"],
    "close --out": lambda tmp, v: ["close", _with_close(tmp), "--out", f"{tmp}/c/{v}.toml"],
    **{f"close [close] {k}": (lambda k: lambda tmp, v: ["close", _with_close(tmp, k, v)])(k)
       for k in ("objective", "margin", "tolerance", "max_iterations", "knobs.min", "knobs.max", "knobs.scale",
                 "knobs.step")},
}
GOLDEN_GDS = ROOT / "layouts" / "golden" / "dual_pixel_revA.gds"


def _netlist(tmp):
    """The kit's netlist of the golden layout's DUALPIX_COL (what `layout` writes beside its GDS)."""
    p = tmp / "net" / "DUALPIX_COL.spice"
    if not p.exists():
        from pixelkit.design import load_design
        from pixelkit.layout.flow import write_netlists
        write_netlists(load_design(REF), ["DUALPIX_COL"], p.parent, "DUALPIX_COL")
    return p


def _raw(tmp):
    """A small ngspice raw file written by the kit (two vectors)."""
    import numpy as np

    from pixelkit.spice.result import Result
    from pixelkit.spice.waveforms import write_waveforms
    p = tmp / "w.raw"
    if not p.exists():
        t = np.linspace(0, 1e-6, 11)
        write_waveforms(Result(t, {"v(a)": t * 1e6, "i(vdd)": -t}, {}), p)
    return p


def _with_close(tmp, key=None, value=None):
    """The reference design with a [close] table (one knob), ``key`` of it set to ``value``."""
    raw = tomllib.loads(REF.read_text())
    knob = {"min": "600 nA", "max": "1.5 uA"}
    close = {"objective": "min power", "knobs": {"pixel.sf_bias": knob}}
    if key is not None:
        if key.startswith("knobs."):
            knob[key[len("knobs."):]] = value
        else:
            close[key] = value
    raw["close"] = close
    p = tmp / f"c{abs(hash((key, repr(value)))) % 10**8}.toml"
    p.write_text(to_toml(raw))
    return p
FAMILIES = ("ratio_pixel.toml", "wdr_pixel.toml", "pixel4t_gf180.toml")


def _cases():
    rng = random.Random(SEED)
    for name in INPUTS:
        for value in CORPUS:
            yield name, value
    for fam in FAMILIES:   # family design files: every key meets a seeded sample of the corpus
        for key in _family_keys(fam):
            for value in rng.sample(CORPUS, 4) + ["1e300", "-1"]:
                yield f"family {fam}:{key}", value


def _run(argv, monkeypatch, capfd):
    import pixelkit.api
    import pixelkit.chip.frame
    import pixelkit.close.revision
    import pixelkit.layout.anylayout
    import pixelkit.layout.library
    import pixelkit.plots.interactive
    import pixelkit.mc.montecarlo
    import pixelkit.spice.executors
    import pixelkit.sweep.run
    from pixelkit.cli import common, entry
    monkeypatch.setattr(pixelkit.sweep.run, "run_tasks", _stub)          # after the axes are validated
    monkeypatch.setattr(pixelkit.spice.executors, "run_tasks", _stub)    # verify: after specs and grid
    monkeypatch.setattr(pixelkit.mc.montecarlo, "simulate_frame", _stub)  # after the corner is applied
    monkeypatch.setattr(pixelkit.chip.frame, "simulate_frame", _stub)
    monkeypatch.setattr(pixelkit.layout.library, "build_chip_cells", _stub)  # after the layout's options
    monkeypatch.setattr(pixelkit.api, "experiment", _stub)   # simulate: after its options (--waveforms)
    monkeypatch.setattr(pixelkit.layout.anylayout, "_start_decks", _stub)   # signoff: after its inputs
    monkeypatch.setattr(pixelkit.plots.interactive, "raw_page", _stub)      # waves: after its options
    monkeypatch.setattr(pixelkit.close.revision, "close_design", _stub)     # close: after [close] and --out (cli.close imports it from there)
    common.WARNINGS.clear()
    try:
        entry([str(a) for a in argv])
        code = 0
    except Accepted:
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    return code, capfd.readouterr().err


def test_fuzz_every_input(tmp_path, monkeypatch, capfd):
    import inspect

    import pixelkit.cli.close
    assert "close.revision import close_design" in inspect.getsource(pixelkit.cli.close), \
        "the close stub (_run) must sit where `pixelkit close` takes close_design from, or every case runs a close"
    monkeypatch.setenv("PIXELKIT_REPORTS", str(tmp_path / "reports"))
    problems, n, refused = [], 0, 0
    for name, value in _cases():
        n += 1
        if name.startswith("family "):
            fam, key = name[len("family "):].split(":")
            argv = ["models", _design_file(tmp_path, fam, key, value)]
        else:
            argv = INPUTS[name](tmp_path, value)
        code, err = _run(argv, monkeypatch, capfd)
        label = f"{name} = {value[:40]!r}"
        if code not in (0, 2):
            problems.append(f"{label}: exit {code}: {err.strip()[-300:]}")
        elif code == 2:
            refused += 1
            lines = [ln for ln in err.strip().splitlines() if not ln.startswith("pixelkit: warning")]
            if "Traceback" in err or not lines or (lines[0].startswith("pixelkit:") and len(lines) != 1):
                problems.append(f"{label}: not a one-line error: {err[-300:]!r}")
        if "internal error" in err or "Traceback" in err:
            problems.append(f"{label}: {err.strip()[-300:]}")
    assert not Path(MARK).exists()
    assert not problems, "\n".join(problems[:40])
    assert n > 500 and refused > n // 2   # the corpus is mostly hostile


@pytest.mark.parametrize("address,ok", [("tcp://127.0.0.1:8786", True), ("127.0.0.1:8786", True),
                                        ("tls://scheduler.example:8786", True), ("tcp://[::1]:8786", True),
                                        ("tcp://host:0", False), ("tcp://host:65536", False), ("tcp://", False),
                                        ("host", False), ("tcp://a b:1", False), ("file:///etc/passwd:1", False),
                                        ("tcp://h:1\n.control", False)])
def test_scheduler_addresses_are_checked_before_connecting(address, ok):
    """The address form Dask documents ([protocol://]host:port); nothing connects in this test."""
    from pixelkit.errors import ConfigError
    from pixelkit.spice.executors import check_address
    if ok:
        assert check_address(address) == address
    else:
        with pytest.raises(ConfigError, match="--scheduler"):
            check_address(address)


def test_the_stub_runs_only_after_validation(tmp_path, monkeypatch, capfd):
    """The harness can tell accepted from refused: a good value reaches the stub (exit 0), a bad one
    does not (exit 2)."""
    code, err = _run(["sweep", REF, "--over", "pixel.sf_bias=300nA,400nA"], monkeypatch, capfd)
    assert code == 0, err
    code, err = _run(["sweep", REF, "--over", "pixel.sf_bias=1e300A"], monkeypatch, capfd)
    assert code == 2 and "sf_bias" in err, err
