"""setup.sh and the README's two commands: CI runs exactly the README's test command; the
set-up refuses what it cannot do in one line before touching anything.

The set-up itself (a virtual environment on Debian's own python3, pip into it only) is
checked by running the README's commands on an isolated clone with Debian's PATH
(docs/setup.md gives the figures and how to repeat it): it needs apt-get and the network.
"""
import re
import subprocess

from conftest import ROOT


def _readme_commands():
    return re.findall(r"```sh\n(.+?)\n```", (ROOT / "README.md").read_text())[:2]


def test_ci_runs_the_readme_test_command():
    main_job, tests = _readme_commands()
    assert main_job.startswith("./setup.sh && .venv/bin/python -m pixelkit ")
    assert tests == "./setup.sh && .venv/bin/python -m pytest"
    lines = [ln for ln in (ROOT / ".ci" / "run").read_text().splitlines() if ln and not ln.startswith("#")]
    assert lines[-1] == tests


def test_setup_refuses_a_bad_argument_and_a_folder_that_is_not_a_venv(tmp_path):
    p = subprocess.run(["bash", str(ROOT / "setup.sh"), "--bogus"], capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and p.stderr.strip() == "setup: unknown argument '--bogus' (allowed: --venv DIR)"
    (tmp_path / "plain").mkdir()
    p = subprocess.run(["bash", str(ROOT / "setup.sh"), "--venv", str(tmp_path / "plain")], capture_output=True,
                       text=True, timeout=600)
    assert p.returncode == 2 and "is not a virtual environment" in p.stderr, p.stderr
    assert not (tmp_path / "plain" / "bin").exists()
