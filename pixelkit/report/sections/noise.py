"""Noise section: the NCDS read-noise budget of each subpixel, analytic against SPICE, and the
output-referred conversion gain against a SPICE charge step."""
from __future__ import annotations

import numpy as np

from ...camera.afe_spicenoise import afe_output_noise
from ...camera.plots import noise_breakdown
from ...camera.spicenoise import output_cg, pixel_noise, sf_gain
from ...physics import fd
from ...physics.noise import chain
from ...techfit.ekv import models_for
from .. import names as N
from ..html import fmt
from .. import plausibility
from . import Checked, Figure, Section, Table

TITLE = "Noise"
_ARR = ("primary", "secondary")


def build(ctx) -> Section:
    d = ctx.design
    a = sf_gain(d)
    sf_models = models_for(d)
    ch = {w: chain(d, w, a, sf_models) for w in _ARR}
    sp = {w: pixel_noise(d, w, a) for w in _ARR}
    cg_sp = output_cg(d, backend=ctx.backend)
    sources = list(ch["primary"]["electrons"])
    budget = [[s.replace("_", " "), ch["primary"]["electrons"][s], ch["secondary"]["electrons"][s]] for s in sources]
    budget += [[N.label("read noise at the column"), ch["primary"]["pixel_e"], ch["secondary"]["pixel_e"]],
               [N.label("read noise with the AFE"), ch["primary"]["afe_e"], ch["secondary"]["afe_e"]]]
    afe_in = afe_output_noise(d)["total_V2"] * (d.afe.c13 / d.afe.c11) ** 2
    budget.append(["read noise with the AFE by SPICE .noise at the AFE phases (e-)",
                   *(float(np.sqrt(sp[w]["pixel_V"] ** 2 + afe_in) / ch[w]["cg_out_V_per_e"]) for w in _ARR)])
    v_reset = d.pixel.v_pd_reset
    versus, flags, resp = [], [], {}
    for w in _ARR:
        r = resp[w] = fd.response(d, w, a, sf_models)
        versus.append([w, 1e3 * ch[w]["pixel_V"], 1e3 * sp[w]["pixel_V"], 1e6 * r["cg_pd_V_per_e"],
                       1e6 * r["cg_out_V_per_e"], 1e6 * cg_sp[w]])
        flag = plausibility.read_noise(w, ch[w]["pixel_e"], ch[w]["electrons"], r["cg_out_V_per_e"], r["c_fd_F"])
        if flag:
            flags.append(flag)
    fig = ctx.figure("noise_breakdown.png")
    noise_breakdown({w: {"noise_e": ch[w]["electrons"]} for w in _ARR}, fig)
    text = [
        "Read noise through the chain with non-correlated double sampling (the reset level comes "
        "from a new FD reset): after PD and FD share charge through TG, FD keeps kT/C_FD (the "
        "common mode of the two resets plus the TG partition), and the reset sample adds another "
        "kT/C_FD; the SF and its load add kT/C_col per sample, and their 1/f noise what the NCDS "
        "difference 2 - 2cos(2 pi f dt) leaves of it. Referred to the PD through the "
        f"small FD, this dominates: charge sharing with a {resp['primary']['c_fd_F'] * 1e15:.2f} fF FD costs the "
        "read noise more than it costs the conversion gain.",
        "Independent path: ngspice .noise of FD as each switch leaves it (BSIM4 noise sources, "
        "the devices' own capacitances) and of the read chain weighted by the NCDS filter; the "
        "output-referred CG against a SPICE transient with a known photo-charge.",
        "Every electron figure here is a column voltage divided by CG_out(0) "
        f"({fmt(1e6 * resp['primary']['cg_out_V_per_e'])} / {fmt(1e6 * resp['secondary']['cg_out_V_per_e'])} uV/e- "
        f"for primary / secondary); {N.cg_jdep(v_reset)} is the PD junction alone at the design's {v_reset:g} V "
        "PD reset (the Design summary gives it at the technology's reference bias too). The Virtual camera's "
        "sigma_d (EMVA) is the same column noise divided by K x LSB instead.",
        "The AFE probe adds the SC amplifier: kT/C of C12 (through the noise gain 1/beta) and C13, "
        "the op-amp's thermal noise folded by autozero over (pi/2) GBW (1 + beta), and its 1/f noise "
        "high-passed by the autozero's 2 - 2cos(2 pi f T) (physics/afe_noise.py); independent path: "
        "ngspice .noise of the AFE cell at its two phase operating points with sampling theory."]
    return Section(
        TITLE, text=text,
        tables=[Table("noise_budget", "Input-referred read noise by source (e- rms)",
                      ["source", "primary", "secondary"], budget),
                Table("noise_vs_spice", "Analytic vs SPICE: read noise at the column and conversion gain",
                      ["subpixel", "read noise at the column, model (mV)", "read noise at the column, SPICE .noise (mV)",
                       N.label(N.cg_jdep(v_reset)), N.label("CG_out(0)"), "CG_out(0) by a SPICE charge step (uV/e-)"],
                      versus)],
        figures=[Figure(fig.name, "Read-noise breakdown (e- rms, input-referred)")],
        flags=flags,
        checked=[*(Checked(f"noise.read_e_{w}", ch[w]["pixel_e"], "e-", tol_rel=0.05, note="read noise at the column")
                   for w in _ARR),
                 *(Checked(f"noise.cg_out_{w}", cg_sp[w], "V/e-", tol_rel=0.02,
                           note="CG_out(0) by a SPICE charge step") for w in _ARR)],
        data={"chain": ch, "spice": sp, "a_sf": a})
