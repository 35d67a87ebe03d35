"""The Python API example of docs/api.md runs as it is, and its outputs are right.

Independent checks: C_A printed from the extracted GDS equals the PD area ratio
written in the design file (15.1 um x 13.55 um over 5 um x 5 um); the exported
deck and the waveform file exist with the documented columns.
"""
import re
import subprocess
import sys

from conftest import ROOT


def test_api_page_example_runs(tmp_path):
    page = (ROOT / "docs" / "api.md").read_text()
    block = re.search(r"<!-- api-example -->\n```python\n(.*?)```", page, re.S).group(1)
    (tmp_path / "designs").symlink_to(ROOT / "designs")
    (tmp_path / "example.py").write_text(block)
    p = subprocess.run([sys.executable, "example.py"], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr[-3000:]
    c_a = float(re.search(r"C_A from the GDS = ([0-9.]+)", p.stdout).group(1))
    assert abs(c_a - (15.1 * 13.55) / (5 * 5)) < 1e-3
    assert re.search(r"primary \d+\.\d mV, secondary \d+\.\d mV", p.stdout)
    assert (tmp_path / "out" / "dual_pixel.csv").read_text().splitlines()[0] == "time_s,v(col_p)_V,v(col_s0)_V"
    assert ".options" in (tmp_path / "out" / "dual_pixel.cir").read_text()
    assert "Warning" not in p.stderr  # the reference design is inside the working range
