"""The DRC deck runner (``pixelkit/layout/signoff/deck_runner.drc``): a deck run through it gives
the report the deck gives when KLayout runs it directly, and its ``pmap`` log query gets the
figure the real ``pmap`` (procps) gives for the same process.

Independent judges: KLayout running the same deck without the runner (the reports compared
item by item) and procps' ``pmap`` called by the deck without the shell backtick the runner
answers. Broken variants: a deck whose rule output differs is told apart by the same comparison
(a wider width check), and a runner that swallowed other shell commands fails the echo check.
"""
import subprocess
import xml.etree.ElementTree as ET

import gdstk
import pytest

from pixelkit.layout.signoff.drc import RUNNER, klayout_binary, parse_report

# a small deck written as the GF180MCU deck is: rules on a source layout, a log line asking the
# shell for the memory in use, another shell command, and pmap read without the backtick
DECK = """
source($input, $topcell)
report("runner check", $report)
deep
m1 = polygons(34, 0)
m1.width(WIDTH.um).output("M1.1", "M1.1 : min. metal1 width")
m1.space(0.23.um).output("M1.2a", "M1.2a : min. metal1 space")
logged = `pmap #{Process.pid} | tail -1`[10,40].strip
real = IO.popen(["pmap", Process.pid.to_s]) { |f| f.readlines.last }[10,40].strip
File.write($out, [logged, real, `echo passed through`.strip].join("\\n"))
"""


@pytest.fixture(scope="module")
def gds(tmp_path_factory):
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    cell = gdstk.Cell("T")
    for x, w in ((0, 0.1), (1, 0.2), (2, 0.3), (2.4, 0.3)):    # two too narrow, two too close
        cell.add(gdstk.rectangle((x, 0), (x + w, 2), layer=34, datatype=0))
    lib.add(cell)
    path = tmp_path_factory.mktemp("runner") / "t.gds"
    lib.write_gds(str(path))
    return path


def _run(tmp, gds, width, through_runner):
    deck = tmp / f"deck_{width}.drc"
    deck.write_text(DECK.replace("WIDTH", str(width)))
    tag = f"{width}_{'runner' if through_runner else 'direct'}"
    report, out = tmp / f"{tag}.lyrdb", tmp / f"{tag}.txt"
    script = ["-r", str(RUNNER), "-rd", f"pixelkit_deck={deck}"] if through_runner else ["-r", str(deck)]
    p = subprocess.run([klayout_binary(), "-b", *script, "-rd", f"input={gds}", "-rd", "topcell=T",
                        "-rd", f"report={report}", "-rd", f"out={out}"], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout[-500:] + p.stderr[-500:]
    items = sorted(ET.tostring(i) for i in ET.parse(report).getroot().iter("item"))
    return parse_report(report), items, out.read_text().splitlines()


def test_the_runner_gives_the_decks_own_report(tmp_path, gds):
    direct, direct_items, _ = _run(tmp_path, gds, 0.23, False)
    runner, runner_items, _ = _run(tmp_path, gds, 0.23, True)
    assert {v.rule: v.count for v in direct} == {"M1.1": 2, "M1.2a": 1}
    assert runner == direct and runner_items == direct_items
    wider, wider_items, _ = _run(tmp_path, gds, 0.35, True)       # another rule: told apart
    assert {v.rule: v.count for v in wider} == {"M1.1": 4, "M1.2a": 1} and wider_items != direct_items


def test_the_runner_answers_pmap_as_pmap_does_and_passes_other_commands(tmp_path, gds):
    _, _, (logged, real, echo) = _run(tmp_path, gds, 0.23, True)
    assert logged.endswith("K") and real.endswith("K")
    assert int(logged[:-1]) == pytest.approx(int(real[:-1]), rel=0.05)
    assert echo == "passed through"
