"""Every generator against its golden netlist (a change detector), and both backends on every
runnable golden deck.

The goldens are written by the code under test (``pixelkit netlists --write``): equality says
nothing changed, not that the netlist is right. What a netlist means is checked elsewhere:
the exported decks give the kit's figures in raw ``ngspice -b`` (``test_export.py``) and the
schematic walks every element of the golden decks parsed as text (``test_report.py``).
"""
import numpy as np
import pytest

from conftest import ROOT
from pixelkit.registry import GENERATORS, golden_text
from pixelkit.spice import simulate


@pytest.mark.parametrize("name", sorted(GENERATORS))
def test_generator_netlist_unchanged(name, ref_design):
    """Change detector: the generated text equals the committed golden deck."""
    golden = (ROOT / "netlists" / f"{name}.cir").read_text()
    assert golden_text(name, ref_design) == golden, \
        f"{name} changed: review, then regenerate with `python -m pixelkit netlists --write`"


@pytest.mark.parametrize("name", sorted(n for n in GENERATORS if n.startswith("bench_")))
def test_backends_agree_within_0_1_mV(name, ref_design):
    """Independent reference: the same deck in ngspice's batch process and in libngspice (shared)."""
    net = GENERATORS[name](ref_design)
    a = simulate(net, backend="batch")
    b = simulate(net, backend="shared")
    assert a.meta["backend"] == "batch" and b.meta["backend"] == "shared"
    volts = [k for k in a.vectors if k.startswith("v(")]
    assert volts and set(volts) <= set(b.vectors)
    t = np.linspace(a.time[0], a.time[-1], 4000)
    worst = max(np.max(np.abs(a.at(k, t) - b.at(k, t))) for k in volts)
    assert worst < 1e-4, f"backends differ by {worst * 1e3:.3f} mV"
