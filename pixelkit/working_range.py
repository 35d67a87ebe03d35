"""The circuit's working range: design values that load but put the pixel outside it.

These are warnings, not errors (a designer may explore there on purpose); each
says the field, the value, the limit and why.

- soft reset: the EC and RST switches are NMOS driven to the supply (or to the boosted
  rail ``pixel.v_gate`` with ``pixel.gate_drive = "boosted"``). A drain
  (reset) level above ``supply - Vth`` cannot be passed through: the source
  stops ``Vth`` (more, with body effect) below the gate and the reset ends in
  subthreshold. The reset level then depends on the reset time and on the
  previous signal (lag), and a result such as the primary/secondary current
  ratio is not that of the hard-reset pixel the kit models. ``vth_n`` is the
  zero-bias threshold, a lower bound of the real one, so the check never
  warns on a hard-reset design.
- PD forward bias: the PD node discharges by ``pixel.swing`` from its reset
  level; below ~0 V its junction forward-biases and clamps the signal.
"""
from __future__ import annotations


def check(design) -> list[str]:
    """Warnings for ``design`` (empty when it is inside the working range)."""
    out = []
    px, tech = design.pixel, design.tech
    from .circuits.devices import gate_high
    gate, vth = gate_high(design), tech.mos.vth_n
    limit = gate - vth
    for field, switch in (("v_pd_reset", "EC"), ("v_fd_reset", "RST")):
        v = getattr(px, field)
        if v > limit:
            out.append(f"pixel.{field} = {v:g} V is above the {switch} gate level ({gate:g} V) minus the "
                       f"NMOS threshold ({vth:g} V, more with body effect) = {limit:.3g} V: the switch ends "
                       "the reset in subthreshold (soft reset), so the reset level depends on the reset time "
                       "and the previous signal and the kit's hard-reset results do not apply; "
                       f"use at most {limit:.3g} V")
    if px.v_pd_reset - px.swing < 0.0:
        out.append(f"pixel.v_pd_reset - pixel.swing = {px.v_pd_reset - px.swing:.3g} V is below 0 V: the "
                   "photodiode forward-biases before the end of its swing and clamps the signal")
    return out
