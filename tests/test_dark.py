"""Dark current per junction, each with its own card's temperature law, against ngspice from 25 to 85 degC.

Independent paths: ngspice's own device models at each temperature - its level-1
diode temperature scaling of a card with the foundry's thermal terms (is, jsw,
xti, eg, n), BSIM4's junction model of the MOS diffusions - against the closed
forms of ``physics/dark.py``; and the decks the kit writes (the PD card at the
deck temperature) against the same closed forms, in both technologies. The
foundry photodiode card is run as the library ships it and flagged when its
reverse current is not thermal.
"""
import numpy as np
import pytest

from pixelkit.circuits.devices import mosfet, photodiode, photodiode_model
from pixelkit.physics.dark import dark_current, diffusion_leakage, doubling_K
from pixelkit.spice import simulate_many
from pixelkit.spice.netlist import Element, Model, Netlist, Op
from pixelkit.tech import load_technology

TEMPS = (25.0, 45.0, 65.0, 85.0)
TECHS = ("c35_thesis", "gf180mcu_3v3")
A, P = 204.6e-12, 57.3e-6          # the primary PD of the reference design


def _op(title, elements, tech, temp_c, models=()):
    return Netlist(title=title, elements=tuple(elements), analysis=Op(), models=tuple(models),
                   includes=tech.models.includes(), temperature_C=temp_c, options=(("gmin", 1e-18),))


@pytest.mark.parametrize("name", TECHS)
def test_pd_dark_current_of_the_decks_matches_the_closed_form(name):
    """The PD card the kit writes into its decks, reverse-biased at the reset bias, at 25 - 85 degC."""
    tech = load_technology(name)
    pd = tech.photodiode
    nets = [_op(f"pd_{name}_{int(t)}", (Element("Vr", ("n", "0"), pd.reset_bias), photodiode("p", "n", A, P, tech)),
                tech, t, photodiode_model(tech, t + 273.15)) for t in TEMPS]
    for t, r in zip(TEMPS, simulate_many(nets)):
        spice = abs(float(r["i(vr)"][0]))
        assert spice == pytest.approx(dark_current(A, P, t + 273.15, pd), rel=0.10), (name, t)


def test_card_law_is_ngspices_own_temperature_scaling():
    """GF180's thermal terms with the foundry card's xti / eg / n: ngspice scales them from tnom = 25 degC."""
    tech = load_technology("gf180mcu_3v3")
    pd = tech.photodiode
    card = Model("dth", "d", (("level", 1), ("is", pd.dark_area), ("jsw", pd.dark_perimeter), ("n", pd.dark_n),
                              ("xti", pd.dark_xti), ("eg", pd.dark_eg), ("cjo", 0.0), ("tnom", 25.0)))
    nets = [_op(f"card_{int(t)}", (Element("Vr", ("n", "0"), pd.reset_bias),
                                   Element("D1", ("0", "n"), "dth", (("area", A), ("pj", P)))), tech, t, (card,))
            for t in TEMPS]
    got = [abs(float(r["i(vr)"][0])) for r in simulate_many(nets)]
    want = [dark_current(A, P, t + 273.15, pd) for t in TEMPS]
    assert np.allclose(got, want, rtol=0.10), (got, want)
    assert got[-1] / got[0] > 1000     # a thermal law: x ~2e4 from 25 to 85 degC
    assert 4.0 < doubling_K(298.15, pd) < 4.6


@pytest.mark.parametrize("name", TECHS)
def test_mos_diffusions_follow_bsim4(name):
    """Drain and source diffusions of an off switch (both at 2 V, bulk at 0): BSIM4 in ngspice vs the closed form."""
    tech = load_technology(name)
    w = 0.6e-6
    nets = [_op(f"dif_{name}_{int(t)}", (Element("Vd", ("d", "0"), 2.0), Element("Vb", ("b", "0"), 0.0),
                                         mosfet("m", "d", "d", "d", "b", w, 0.5e-6, tech)), tech, t)
            for t in TEMPS]
    got = [abs(float(r["i(vb)"][0])) for r in simulate_many(nets)]
    want = [2 * diffusion_leakage(w, tech, t + 273.15) for t in TEMPS]
    assert np.allclose(got, want, rtol=0.10), (got, want)
    assert 300 < got[-1] / got[0] < 3000      # x680: doubling every 6.4 K (not the PD's law in either technology)


def test_foundry_card_with_a_tunnelling_current_is_flagged():
    """GF180's diode_nw2ps_03v3 as shipped: its reverse current falls from 25 to 65 degC and exceeds its own
    thermal terms 10^4-fold; the kit flags it and writes its own card (thermal terms only)."""
    from pixelkit.techfit.pdcard import check
    tech = load_technology("gf180mcu_3v3")
    c = check(tech)
    assert c["falls_with_temperature"] and c["card_over_thermal_25C"] > 1e3 and not c["thermal"]
    assert "not a thermal generation current" in c["flag"]
    assert tech.photodiode.builtin_model and tech.photodiode.spice_model != "diode_nw2ps_03v3"
    assert check(load_technology("c35_thesis")) is None      # no foundry card: nothing to measure
    pd = tech.photodiode
    thermal = Model("dth", "d", (("level", 1), ("is", pd.dark_area), ("jsw", pd.dark_perimeter), ("xti", 3.0),
                                 ("eg", 1.18), ("n", 1.01), ("cjo", 0.0), ("tnom", 25.0)))
    ok = check(tech, card="dth", models=(thermal,))     # a thermal card of the same size passes
    assert ok["thermal"] and "flag" not in ok and 0.5 < ok["card_over_thermal_25C"] < 2
