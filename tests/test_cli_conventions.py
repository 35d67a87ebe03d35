"""The command-line convention: design positional, --json everywhere (errors too), one --out,
--jobs/--backend where SPICE runs, distinct exit statuses, working-range warnings, progress.

The expected exit statuses and JSON fields are the documented convention
(docs/cli-conventions.md, pixelkit/errors.py), not the code's output;
the soft-reset limit is derived here from the technology (supply - Vth).
"""
import json
import os
import re
from pathlib import Path

import click
import pytest

from conftest import REF
from pixelkit.cli import register_all
from pixelkit.cli.common import main

register_all()

#: Commands that run SPICE (directly or through the gap surrogate).
SPICE_COMMANDS = {"simulate", "run", "array", "size", "regress", "report", "gap predict", "gap diagnose",
                  "gap selftest"}


def _commands(group=main, prefix=""):
    for name, cmd in group.commands.items():
        full = f"{prefix}{name}"
        if isinstance(cmd, click.Group):
            yield from _commands(cmd, full + " ")
        else:
            yield full, cmd


def _opts(cmd):
    return {o for p in cmd.params for o in getattr(p, "opts", [])}


def test_every_command_follows_the_convention():
    seen = set()
    for name, cmd in _commands():
        seen.add(name)
        opts = _opts(cmd)
        assert "--json" in opts, f"{name} has no --json"
        assert not {"--design", "--out-dir", "--output", "-o"} & opts, f"{name}: {opts}"
        designs = [p for p in cmd.params if p.name == "design"]
        if designs:
            assert isinstance(designs[0], click.Argument), f"{name}: design must be positional"
        if name in SPICE_COMMANDS:
            assert {"--jobs", "--backend"} <= opts, f"{name} runs SPICE without --jobs/--backend"
    assert SPICE_COMMANDS <= seen


def _json(out):
    return json.loads(out)


def test_missing_file_error_as_json_with_field_value_and_status(cli, tmp_path):
    code, out, err = cli("models", tmp_path / "nope.toml", "--json")
    assert code == 2
    e = _json(out)
    assert e["exit_status"] == 2 and e["field"] == "design" and str(tmp_path / "nope.toml") in e["value"]
    assert e["allowed"] and e["error"] and "Traceback" not in err


def test_bad_field_error_as_json(cli, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(REF.read_text().replace('swing = "1.5 V"', 'swing = "1.5 A"'))
    code, out, err = cli("simulate", bad, "--json")
    e = _json(out)
    assert code == 2 and e["field"] == "pixel.swing" and e["exit_status"] == 2


def test_usage_error_as_json_and_plain(cli):
    code, out, err = cli("array", REF, "--rows", "0", "--json")
    e = _json(out)
    assert code == 2 and e["field"] == "--rows" and e["exit_status"] == 2
    code, out, err = cli("array", REF, "--rows", "0")
    assert code == 2 and "--rows" in err and out == ""


def test_list_commands_emit_json(cli):
    code, out, err = cli("netlists", "--json")
    assert code == 0 and "bench_dual_pixel" in _json(out)["generators"]


def _in_process(argv, capsys):
    from pixelkit.cli import entry
    with pytest.raises(SystemExit) as ex:
        entry(argv)
    return ex.value.code, capsys.readouterr()


def test_exit_statuses_are_distinct(capsys):
    """1 difference, 2 user error, 3 internal fault, 4 simulation failed (errors.py, docs/cli-conventions.md)."""
    from pixelkit.errors import ConfigError, RegressionFound, SimulationError

    raised = {"regression": RegressionFound("2 figures changed"),
              "user": ConfigError("d.toml", "pixel.swing", 9.0, "a value < 5 V"),
              "internal": RuntimeError("a bug"),
              "simulation": SimulationError("coarse8", ".tran", "Timestep too small", what="the bench at 1 nA")}

    @main.command("_raise_for_test")
    @click.argument("what")
    @click.option("--json", "as_json", is_flag=True)
    def _raise(what, as_json):
        raise raised[what]

    try:
        codes = {}
        for what in raised:
            code, cap = _in_process(["_raise_for_test", what, "--json"], capsys)
            codes[what] = code
            assert json.loads(cap.out)["exit_status"] == code
        assert codes == {"regression": 1, "user": 2, "internal": 3, "simulation": 4}
        code, cap = _in_process(["_raise_for_test", "internal"], capsys)
        assert code == 3 and "internal error" in cap.err and "Traceback" not in cap.err
    finally:
        del main.commands["_raise_for_test"]


def _variant(tmp_path, v_pd, v_fd, name="v.toml"):
    text = REF.read_text()
    text = text.replace('v_pd_reset = "2.0 V"', f'v_pd_reset = "{v_pd} V"')
    text = text.replace('v_fd_reset = "2.0 V"', f'v_fd_reset = "{v_fd} V"')
    p = tmp_path / name
    p.write_text(text)
    return p


def test_soft_reset_is_warned_with_the_reason(cli, tmp_path, ref_design):
    t = ref_design.tech
    limit = t.supply - t.mos.vth_n  # hard reset needs the drain below gate - Vth
    assert 2.0 < limit < 2.8
    code, out, err = cli("models", _variant(tmp_path, 2.8, 2.0), "--json")
    assert code == 0
    w = _json(out)["warnings"]
    assert len(w) == 1 and "pixel.v_pd_reset" in w[0] and "soft reset" in w[0] and f"{limit:.3g}" in w[0]
    assert "warning" in err
    code, out, err = cli("models", REF, "--json")
    assert code == 0 and "warnings" not in _json(out) and "warning" not in err


#: the kit run with the former photodiode card (sidewall FCS 0.5: the charge jumps when an over-exposed
#: PD forward-biases, so ngspice really stops there; issue 27 made the card continuous)
_FORMER_CARD = ("import sys, pixelkit.circuits.devices as dv; dv.sidewall_fc = lambda pd: 0.5; "
                "from pixelkit.cli import entry; sys.argv = ['pixelkit'] + sys.argv[1:]; entry()")


def test_failed_simulation_keeps_deck_and_log_in_user_terms(tmp_path):
    """3.3 V resets with the former PD card: ngspice stops (timestep too small) on the brightest coarse
    point, a real failure. The experiment goes on without it (issue 27) and names it in user terms: the
    photocurrent, the primary's own forward-biased node, and the folder where its deck and log are kept."""
    import subprocess
    import sys
    design = _variant(tmp_path, 3.3, 3.3, "soft33.toml")
    env_cwd = tmp_path / "work"
    env_cwd.mkdir()
    out = {}
    for fmt in ("--json", None):
        p = subprocess.run([sys.executable, "-c", _FORMER_CARD, "simulate", str(design)] + ([fmt] if fmt else []),
                           capture_output=True, text=True, cwd=env_cwd, timeout=900)
        assert p.returncode == 0, p.stdout + p.stderr
        out[fmt] = p
    e = _json(out["--json"].stdout)
    assert any("soft reset" in w for w in e["warnings"])
    assert e["failed_points"], e
    x = e["failed_points"][0]
    assert x["sweep"] == "coarse" and x["iph_primary_A"] > 1e-9
    assert "primary node x1.xp.pd" in x["message"] and "forward-biased" in x["message"]
    assert x["tried"] and "gmin" in x["tried"][0]
    folder = Path(x["folder"])
    assert folder.parent == Path(os.environ["PIXELKIT_CACHE"]) / "failed"
    assert "FAILED point" in out[None].stdout          # each failure its own folder: the text run's own
    assert f"kept in {folder.parent}{os.sep}coarse" in out[None].stdout
    assert not (env_cwd / "reports").exists()   # nothing written into the current folder
    assert "timestep too small" in (folder / "ngspice.log").read_text().lower()
    assert ".options" in (folder / "deck.cir").read_text() and (folder / "models").is_dir()


def test_progress_is_plain_lines_off_a_terminal_and_quiet_with_json(monkeypatch, capsys):
    """Off a terminal (pytest's stderr) progress is whole lines, never a carriage return; inside a
    command's bar the library's bars are silent; --quiet / --json (set_quiet) and
    PIXELKIT_PROGRESS=0 silence everything."""
    from pixelkit import progress
    monkeypatch.delenv("PIXELKIT_PROGRESS", raising=False)
    assert progress.mode() == "lines"
    with progress.command_bar("outer", total=2, unit="steps") as bar:
        list(progress.progress(range(3), desc="inner"))
        bar.update(2)
    err = capsys.readouterr().err
    lines = [re.sub(r"\d\d:\d\d", "T", ln) for ln in err.splitlines()]   # elapsed times vary
    assert "\r" not in err and lines == ["outer: 0/2 steps [T]", "outer: done 2/2 steps in T"], err
    progress.set_quiet(True)  # what --quiet and --json do
    try:
        list(progress.progress(range(3), desc="hidden"))
        assert capsys.readouterr().err == ""
    finally:
        progress.set_quiet(False)
    monkeypatch.setenv("PIXELKIT_PROGRESS", "0")
    list(progress.progress(range(3), desc="hidden"))
    assert capsys.readouterr().err == ""


def test_outputs_default_under_reports_design(cli, tmp_path):
    code, out, err = cli("netlist", REF, "--json", cwd=tmp_path)
    assert code == 0, err
    assert (tmp_path / "reports" / "dual_pixel_revA" / "bench_dual_pixel.cir").is_file()


def _big_pd(tmp_path):
    text = REF.read_text()
    head, sec = text.split("[secondary]", 1)
    sec = sec.replace('pd_width = "5 um"', 'pd_width = "6 um"', 1).replace('pd_height = "5 um"', 'pd_height = "6 um"', 1)
    bad = tmp_path / "big.toml"
    bad.write_text(head + "[secondary]" + sec)
    return bad


def test_undrawable_geometry_refused_by_layout(cli, tmp_path):
    """A 6 x 6 um PD in an 8 um cell (issue 12) cannot be drawn (issue 28: a layout error):
    `layout` exits 2, JSON naming the field with the value as the user wrote it, nothing written."""
    code, out, err = cli("layout", _big_pd(tmp_path), "--json", cwd=tmp_path)
    e = _json(out)
    assert code == 2 and e["exit_status"] == 2, out + err
    assert e["field"].startswith("secondary.") and e["value"] in ("6 um", "8 um")
    assert "e-0" not in e["error"]  # no SI floats such as 9.999999999999999e-06
    assert not (tmp_path / "reports").exists()


@pytest.mark.parametrize("command", ["models", "netlist"])
def test_undrawable_geometry_runs_with_a_warning_in_circuit_commands(cli, tmp_path, command):
    """The same design through circuit-only commands: it runs (a designer's "what if"), and the
    JSON carries the warning that `layout` refuses it."""
    code, out, err = cli(command, _big_pd(tmp_path), "--json", cwd=tmp_path)
    assert code == 0, err
    w = " ".join(_json(out).get("warnings", []))
    assert "transistors_fit" in w and "pixelkit layout" in w
