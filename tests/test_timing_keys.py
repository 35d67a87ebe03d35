"""Timing keys of the design file ([primary.timing], [secondary.timing]).

Independent path: the control waveforms are read back from the deck text (the PWL
points ngspice gets), not from the timing objects that wrote them; the bad-input
cases are timings a designer can check by hand against the row time 1/f_read.
"""
import re

import pytest

from conftest import REF
from former_design import untimed
from pixelkit.design import load_design
from pixelkit.errors import ConfigError


def _with(tmp_path, table: str, lines: str, name="d.toml", extra=()):
    text = untimed()
    for a, b in extra:
        assert a in text
        text = text.replace(a, b)
    p = tmp_path / name
    p.write_text(text + f"\n[{table}]\n{lines}\n")
    return p


def _pwl(deck: str, source: str) -> list:
    line = next(ln for ln in deck.splitlines() if ln.split()[:1] == [source])
    nums = [float(x) for x in re.findall(r"[-+0-9.e]+", line.split("PWL(", 1)[1])]
    return list(zip(nums[::2], nums[1::2]))


def _rises(points, vdd=3.3):
    """Instants at which the waveform starts to rise to ``vdd`` and to fall from it."""
    up = [a[0] for a, b in zip(points, points[1:]) if a[1] == 0 and b[1] == vdd]
    down = [a[0] for a, b in zip(points, points[1:]) if a[1] == vdd and b[1] == 0]
    return up, down


def test_defaults_are_the_former_fractions_of_the_row(tmp_path):
    """No timing table: S1 0.1 - 0.4, RST 0.45 - 0.55, S2 0.6 - 0.9, RS 0.02 - 0.98 of the row
    (the thesis [Thesis2019] bench's read), read back from the deck's sources; no precharge."""
    from pixelkit.circuits.testbench import dual_pixel_bench, timings
    (tmp_path / "u.toml").write_text(untimed())
    ref_design = load_design(tmp_path / "u.toml")
    deck = dual_pixel_bench(ref_design, 1e-9, 1e-11, with_afe=True).text()
    t = timings(ref_design, ref_design.experiment.t_window)["primary"]
    t0, tr = t.row(0), 2e-6                       # 500 kHz
    up, down = _rises(_pwl(deck, "Vs1_p"))
    assert up[0] == pytest.approx(t0 + 0.1 * tr) and down[0] == pytest.approx(t0 + 0.4 * tr)
    up, down = _rises(_pwl(deck, "Vrs_p"))
    assert up[0] == pytest.approx(t0 + 0.02 * tr) and down[0] == pytest.approx(t0 + 0.98 * tr)
    up, down = _rises(_pwl(deck, "Vs2_s"))       # secondary: 1 MHz
    ts = timings(ref_design, ref_design.experiment.t_window)["secondary"]
    assert down[0] == pytest.approx(ts.row(0) + 0.9e-6)
    assert "Vpre" not in deck and "Xpre_" not in deck


def test_settled_read_reaches_the_deck(ref_design):
    """The settled read (designs/dual_pixel_revA.toml): precharge switch per column, its pulse inside S1."""
    from pixelkit.circuits.testbench import dual_pixel_bench, timings
    deck = dual_pixel_bench(ref_design, 1e-9, 1e-11, with_afe=True).text()
    t = timings(ref_design, ref_design.experiment.t_window)
    for s, kind in (("p", "primary"), ("s", "secondary")):
        up, down = _rises(_pwl(deck, f"Vpre_{s}"))
        tk = getattr(ref_design, kind).timing
        assert up[0] == pytest.approx(t[kind].row(0) + tk.pre_on) and down[0] == pytest.approx(t[kind].row(0) + tk.pre_off)
        s1 = _rises(_pwl(deck, f"Vs1_{s}"))
        assert s1[0][0] <= up[0] < down[0] < s1[1][0]
    assert deck.count("Xpre_col_") == 1 + ref_design.secondary_per_pixel


def test_keys_reach_the_deck(tmp_path):
    """Every key moves its own edge in the deck; the secondary keeps its own read."""
    from pixelkit.circuits.testbench import dual_pixel_bench
    p = _with(tmp_path, "primary.timing", 's1_on = "0.1 us"\ns1_off = "0.85 us"\nt_tg = "0.7 us"\n'
              'edge = "5 ns"\nt_reset = "2 us"')
    d = load_design(p)
    deck = dual_pixel_bench(d, 1e-9, 1e-11).text()
    tg = _pwl(deck, "Vtg_p")
    up, down = _rises(tg)
    assert down[0] - up[0] == pytest.approx(0.7e-6)
    assert any(b[0] - a[0] == pytest.approx(5e-9) for a, b in zip(tg, tg[1:]) if a[1] != b[1])
    ec = _pwl(deck, "Vec_p")
    assert _rises(ec)[1][0] == pytest.approx(2e-6)   # exposure starts when EC opens
    from pixelkit.circuits.testbench import timings
    t = timings(d, d.experiment.t_window)
    assert t["primary"].s1_window(0)[1] - t["primary"].row(0) == pytest.approx(0.85e-6)
    assert t["secondary"].s1_window(0)[1] - t["secondary"].row(0) == pytest.approx(0.4e-6)
    # both arrays still transfer together (the secondary's exposure starts later)
    assert t["primary"].t_tx == pytest.approx(t["secondary"].t_tx)


def test_ec_hold_key(tmp_path, ref_design):
    from pixelkit.circuits.array import frame_timings
    from pixelkit.circuits.testbench import timings
    assert frame_timings(ref_design, 16e-6, 2)["primary"].ec_hold
    assert not timings(ref_design, 16e-6)["primary"].ec_hold
    d = load_design(_with(tmp_path, "primary.timing", "ec_hold = false"))
    assert not frame_timings(d, 16e-6, 2)["primary"].ec_hold and frame_timings(d, 16e-6, 2)["secondary"].ec_hold
    d = load_design(_with(tmp_path, "secondary.timing", "ec_hold = true", "e.toml"))
    assert timings(d, 16e-6)["secondary"].ec_hold


BAD = [
    # (table, lines, extra replacements, field named, words in what fits)
    ("primary.timing", 's2_off = "1.8 us"', [('f_read = "500 kHz"', 'f_read = "2 MHz"')],
     "primary.timing.s2_off", "inside the row"),                                   # a clock too fast
    ("primary.timing", 'rst_on = "0.7 us"', [], "primary.timing.rst_on", "without overlap"),   # S1 / RST overlap
    ("secondary.timing", 's1_on = "0.5 us"\ns1_off = "0.3 us"', [], "secondary.timing.s1_off",
     "longer than its edge"),                                                        # out of order
    ("primary.timing", 'edge = "250 ns"', [], "primary.timing.edge", "shorter than every phase"),           # an edge longer than a phase
    ("primary.timing", 's1_off = "0.215 us"', [], "primary.timing.s1_off", "non-overlap"),  # AFE cannot fit
    ("secondary.timing", 'rs_on = "0 s"\nrs_off = "0.995 us"', [], "secondary.timing.rs_off", "next row"),
    ("primary.timing", 't_tg = "10 us"\nt_gap = "7 us"', [], "experiment.t_window", "t_tg + t_gap"),
    ("primary.timing", 's1_off = "3 s"', [], "primary.timing.s1_off", "1 s"),
]


@pytest.mark.parametrize("table,lines,extra,field,words", BAD,
                         ids=["clock", "overlap", "order", "edge", "nonoverlap", "next_row", "exposure", "huge"])
def test_bad_timing_is_refused_at_load(tmp_path, table, lines, extra, field, words):
    with pytest.raises(ConfigError) as e:
        load_design(_with(tmp_path, table, lines, extra=extra))
    msg = str(e.value)
    assert field in e.value.field or field in msg, msg
    assert words in msg and "\n" not in msg, msg


def test_same_file_within_the_rules_loads(tmp_path):
    """The checks are not too strict: the 'clock' case with its read scaled to the 2 MHz row loads."""
    p = _with(tmp_path, "primary.timing", 'rs_on = "10 ns"\ns1_on = "50 ns"\ns1_off = "200 ns"\nrst_on = "220 ns"\n'
              'rst_off = "270 ns"\ns2_on = "290 ns"\ns2_off = "450 ns"\nrs_off = "480 ns"',
              extra=[('f_read = "500 kHz"', 'f_read = "2 MHz"')])
    assert load_design(p).primary.timing.s2_off == pytest.approx(450e-9)


def test_bad_timing_exits_2_before_simulating(tmp_path, cli):
    p = _with(tmp_path, "primary.timing", 's2_off = "1.8 us"', extra=[('f_read = "500 kHz"', 'f_read = "2 MHz"')])
    code, out, err = cli("simulate", p, "--json")
    assert code == 2 and '"field": "primary.timing.s2_off"' in out and "1.8 us" in out
    code, out, err = cli("sweep", REF, "--over", "t_exp=500n", "--out", tmp_path / "sw")
    lines = err.strip().splitlines()   # the sweep's progress lines, then the one error line
    assert code == 2 and "t_exp" in lines[-1] and "t_tg + t_gap" in lines[-1] and "Traceback" not in err
    assert [ln for ln in lines if ln.startswith("pixelkit:")] == lines[-1:]
