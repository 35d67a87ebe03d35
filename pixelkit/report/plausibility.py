"""Figures far outside what a modern pixel of the kind reaches, each flagged with its reason.

A design can be simulated correctly and still be a poor pixel; a figure a reviewer would
not believe without an explanation gets one: which parts of the budget make it, and what
would lower it. The limits are deliberately loose (an order of magnitude above what
current global-shutter pixels reach), so a flag means "look at this", not "slightly high".
"""
from __future__ import annotations

#: Read noise (e- rms) above which a 5T global-shutter pixel is flagged: current ones reach a few
#: e- (pinned PD, true CDS) to a few tens of e- (voltage-domain storage, as this pixel).
READ_NOISE_E = 50.0
#: DSNU (e- rms) above which it is flagged: current pixels stay within a few e- to a few tens.
DSNU_E = 100.0

_KTC = ("reset_common_mode", "tg_partition", "fd_reset_ncds")
_WHY = {"reset_common_mode": "the common mode of the two resets", "tg_partition": "the TG partition",
        "fd_reset_ncds": "the second FD reset (non-correlated double sampling cannot cancel it)",
        "sf_load_thermal": "the SF and its load (thermal)", "sf_load_flicker": "the SF and its load (1/f)",
        "dark_shot": "dark-current shot noise", "fd_leakage_shot": "FD leakage shot noise"}


def read_noise(which: str, total_e: float, electrons: dict, cg_out: float, c_fd: float) -> str | None:
    """The flag of a read noise ``total_e`` (e-) with its budget ``electrons`` (e- by source), or None."""
    if total_e <= READ_NOISE_E:
        return None
    top = sorted(electrons.items(), key=lambda kv: -kv[1])[:3]
    parts = ", ".join(f"{_WHY.get(k, k.replace('_', ' '))} {v:.0f} e-" for k, v in top)
    text = (f"{which} read noise {total_e:.0f} e- rms, far above what a modern global-shutter pixel reaches "
            f"(a few to a few tens of e-). Largest parts: {parts}.")
    if top[0][0] in _KTC:
        text += (f" They are kT/C of the {c_fd * 1e15:.2f} fF storage node FD referred to the photodiode "
                 f"through CG_out(0) = {cg_out * 1e6:.2f} uV/e-: in electrons they fall as C_FD grows towards the PD "
                 "node's capacitance (sqrt(kT / C_FD) (C_PD,node + C_FD) / q is smallest at C_FD = C_PD,node); a "
                 "pinned photodiode with true correlated double sampling removes the reset terms.")
    return text


def dsnu(which: str, dsnu_e: float, what: str) -> str | None:
    if dsnu_e <= DSNU_E:
        return None
    return f"{which} DSNU {dsnu_e:.0f} e- rms ({what}), far above what a modern pixel reaches (a few e- to a few tens)."
