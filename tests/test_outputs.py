"""What a designer takes out: waveform files, files honouring the umask, deterministic GDS,
and the design-file reference that cannot drift from the schema.

Independent paths: the raw waveform file is loaded by ngspice itself (its own
``load`` command), the CSV is checked against the raw values; the file mode is
the POSIX rule (0666 & ~umask); the reference is regenerated from the schema.
"""
import json
import os
import subprocess

import numpy as np
import pytest

from conftest import REF, ROOT


@pytest.fixture(scope="module")
def array_run(tmp_path_factory):
    from conftest import run_cli
    d = tmp_path_factory.mktemp("wave")
    code, out, err = run_cli("simulate", REF, "--waveforms", d / "w.csv", "--json")
    assert code == 0, out + err
    code2, out2, err2 = run_cli("simulate", REF, "--waveforms", d / "w.raw", "--json")  # cached now
    assert code2 == 0, out2 + err2
    return d, json.loads(out)


def test_waveform_csv_has_time_and_unit_named_columns(array_run):
    d, r = array_run
    header = (d / "w.csv").read_text().splitlines()[0].split(",")
    assert header[0] == "time_s"
    assert {"v(col_p)_V", "v(col_s0)_V", "v(col_s2)_V", "v(x1.xp.pd)_V", "i(vdd)_A"} <= set(header)
    assert all(h.endswith(("_V", "_A")) for h in header[1:])
    data = np.loadtxt(d / "w.csv", delimiter=",", skiprows=1)
    assert data.shape[1] == len(header) and np.all(np.diff(data[:, 0]) > 0)


def test_raw_waveforms_load_in_ngspice_and_match_the_csv(array_run, tmp_path):
    d, _ = array_run
    header = (d / "w.csv").read_text().splitlines()[0].split(",")
    data = np.loadtxt(d / "w.csv", delimiter=",", skiprows=1)
    k = len(data) // 2
    (tmp_path / "load.cir").write_text(
        f"* load test\n.control\nload {d / 'w.raw'}\nprint length(time)\nprint v(col_p)[{k}]\n.endc\n.end\n")
    p = subprocess.run(["ngspice", "-b", "load.cir"], cwd=tmp_path, capture_output=True, text=True, timeout=60)
    vals = [ln.split("=")[1] for ln in p.stdout.splitlines() if " = " in ln]
    assert len(vals) == 2, p.stdout[-1500:]
    assert int(float(vals[0])) == len(data)
    assert abs(float(vals[1]) - data[k, header.index("v(col_p)_V")]) < 1e-9


def test_written_files_honour_the_umask(tmp_path):
    from pixelkit.fileio import atomic_target, commit, write_atomic
    old = os.umask(0o027)
    try:
        a = write_atomic(tmp_path / "a.txt", "x")
        b = commit(*atomic_target(tmp_path / "b.bin"))
    finally:
        os.umask(old)
    assert a.stat().st_mode & 0o777 == 0o640 and b.stat().st_mode & 0o777 == 0o640


def test_gds_writing_is_deterministic(tmp_path, ref_design):
    from pixelkit.layout.library import build_library
    from pixelkit.layout.flow import write_gds
    a = write_gds(build_library(ref_design, 2, 2), tmp_path / "a.gds")
    mtime = a.stat().st_mtime_ns
    b = write_gds(build_library(ref_design, 2, 2), tmp_path / "b.gds")
    assert a.read_bytes() == b.read_bytes()
    os.utime(a, ns=(mtime - 10**9, mtime - 10**9))
    write_gds(build_library(ref_design, 2, 2), a)  # unchanged geometry: the file is left alone
    assert a.stat().st_mtime_ns == mtime - 10**9


def test_design_reference_is_the_generated_one():
    from pixelkit.schema_doc import DOC_PATH, generate
    committed = (ROOT / DOC_PATH).read_text()
    assert committed == generate(), "regenerate with `python3 -m pixelkit.schema_doc --write`"


def test_design_reference_lists_every_field_of_the_reference_design():
    """Every key written in the reference design file appears in the reference (with its table)."""
    import tomllib
    doc = (ROOT / "docs" / "design-file.md").read_text()
    raw = tomllib.loads(REF.read_text())

    def walk(table, path):
        for k, v in table.items():
            if isinstance(v, dict):
                named = path in ("spec.", "close.knobs.")   # [spec.<name>]: the names are the designer's
                key = (f"{path}<design key>" if path == "close.knobs." else f"{path}<name>") if named else path + k
                assert f"## `[{key}]`" in doc or any(f"## `[{key}.<{n}>]`" in doc for n in ("name", "design key")), key
                walk(v, f"{key}.")
            elif path != "close.knobs.":   # a knob as two bounds: its name is a design key
                assert f"| `{k}` |" in doc, path + k
    walk(raw, "")
    assert "**required**" in doc and ">= 1" in doc


def test_every_design_file_field_has_a_meaning():
    """Each field of the dual-pixel, WDR and ratio design files (and their tables) carries a ``doc``, so
    the generated reference has no empty meaning; a planted field without one is found."""
    from dataclasses import dataclass

    from pixelkit.schema import qty, table
    from pixelkit.schema_doc import undocumented
    assert undocumented() == []

    @dataclass(frozen=True)
    class Inner:
        x: float = qty("m", 1.0, doc="documented")
        y: float = qty("m", 1.0)

    @dataclass(frozen=True)
    class Outer:
        inner: Inner = table(Inner, default=Inner, doc="a table")
    assert [m.split(": ")[1] for m in undocumented(Outer)] == ["inner.y"]


def test_names_too_long_for_the_file_system_are_one_line_user_errors(tmp_path):
    """A path component over the file system's NAME_MAX makes the OS raise ENAMETOOLONG,
    which Path.is_file() passes on: every user path the kit tests, read or written, must
    turn it into a PixelkitError naming the path, never an internal error."""
    from pixelkit.camera.emva_export import check_target
    from pixelkit.chip.scene import load_map
    from pixelkit.design import load_design
    from pixelkit.errors import PixelkitError
    from pixelkit.fileio import check_output, path_kind
    from pixelkit.gap.data import read_table
    from pixelkit.gap.emva import analyse
    long = tmp_path / ("9" * 300)
    assert path_kind(long) is None
    design = load_design(REF)
    for call in (lambda: check_output(long / "out.json"), lambda: check_target(long),
                 lambda: load_map(f"{long}.csv"), lambda: analyse(long),
                 lambda: read_table(f"{long}.csv", design, measured=True)):
        with pytest.raises(PixelkitError) as err:
            call()
        assert "999" in str(err.value) and "\n" not in str(err.value)
