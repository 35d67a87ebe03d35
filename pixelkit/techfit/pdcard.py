"""Is a foundry photodiode card's reverse current a thermal one? Measured with ngspice, flagged if not.

A photodiode's dark current is a thermal generation / diffusion current: it
rises steeply with temperature (doubling every 4 - 10 K). A foundry diode card is
fitted for circuit design, not for imaging, and may carry a reverse current of
another kind: GF180MCU's ``diode_nw2ps_03v3`` has a tunnelling term (jtun,
jtunsw, ntun = 22, xtitun = -46) that dominates at the PD's reverse bias and
*falls* with temperature. ``check`` runs the card as the library ships it
(reverse-biased at the technology's reset bias, 100 x 100 um, at 25 and 65 degC)
and compares it with the thermal terms the kit uses (``physics.dark``): the card
is flagged when its current falls with temperature or exceeds the thermal terms
tenfold at 25 degC. Two small DC decks, cached by the engine.
"""
from __future__ import annotations

from ..physics.dark import dark_current
from ..spice.netlist import Element, Netlist, Op

SIDE = 100e-6
TEMPS_C = (25.0, 65.0)


def _deck(tech, temp_c: float, card: str, models: tuple) -> Netlist:
    pd = tech.photodiode
    includes = tuple(i for i in tech.models.includes() if i.kind == "lib" and "diode" in i.section) or \
        tech.models.includes()
    el = (Element("Vr", ("n", "0"), pd.reset_bias),
          Element("D1", ("0", "n"), card, (("area", SIDE * SIDE), ("pj", 4 * SIDE))))
    return Netlist(title=f"pdcard_{int(temp_c)}", elements=el, analysis=Op(), includes=includes, models=models,
                   temperature_C=temp_c, options=(("gmin", 1e-18),))


def check(tech, backend: str = "batch", card: str | None = None, models: tuple = ()) -> dict | None:
    """The card's reverse current against the thermal terms, and the verdict; None without a foundry card.

    ``card``/``models``: another card to measure (its name, and its .model if the library lacks it)."""
    from ..spice import simulate_many
    pd = tech.photodiode
    card = card or pd.foundry_card
    if not card:
        return None
    res = simulate_many([_deck(tech, t, card, models) for t in TEMPS_C], backend=backend)
    card = [abs(float(r["i(vr)"][0])) for r in res]
    thermal = [dark_current(SIDE * SIDE, 4 * SIDE, t + 273.15, pd) for t in TEMPS_C]
    falls = card[1] < card[0]
    excess = card[0] / thermal[0]
    thermal_card = not falls and excess < 10.0
    out = {"card": card, "bias_V": pd.reset_bias, "temps_C": list(TEMPS_C),
           "card_A_per_1e4um2": card, "thermal_A_per_1e4um2": thermal, "card_over_thermal_25C": excess,
           "falls_with_temperature": falls, "thermal": thermal_card}
    if not thermal_card:
        out["flag"] = (f"{card}: its reverse current at {pd.reset_bias:g} V is not a thermal generation "
                       f"current ({card[0] * 1e12:.3g} pA per 100 x 100 um at 25 degC, {excess:.3g} x the card's "
                       f"thermal terms, {'falling' if falls else 'rising'} to {card[1] * 1e12:.3g} pA at 65 degC): "
                       f"the kit uses the thermal terms (dark_law = {pd.dark_law})")
    return out
