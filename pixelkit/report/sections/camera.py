"""Virtual camera section: EMVA 1288 figures of both arrays, photon transfer and SNR curves.

Every figure that also appears elsewhere in the report carries its name from ``report.names``;
the relation between this section's sigma_d (EMVA) and the Noise section's read noise at the
column (the same column noise, divided by K x LSB instead of CG_out(0)) is stated with the
numbers, and so is what the model's DSNU includes.
"""
from __future__ import annotations

from ...camera.plots import ptc, snr
from ...camera.run import camera, summary
from .. import names as N
from .. import plausibility
from . import Checked, Figure, Section, Table

TITLE = "Virtual camera: EMVA 1288 figures"
_ARR = ("primary", "secondary")


def _rows(s: dict) -> list:
    def both(fn):
        return [fn(s[w]) for w in _ARR]
    return [
        ["K (DN/e-)", *both(lambda f: f["k_dn_per_e"])],
        [N.label("K x LSB"), *both(lambda f: f["k_dn_per_e"] * f["lsb_V"] * 1e6)],
        [N.label("CG_out(0)"), *both(lambda f: f["cg_out_V_per_e"] * 1e6)],
        [N.label("sigma_d (EMVA)"), *both(lambda f: f["read_noise_e"])],
        [N.label("read noise at the column"), *both(lambda f: f["read_noise_chain_e"])],
        ["QE eta", *both(lambda f: f["qe"])],
        [N.label("mu_e.sat (EMVA)"), *both(lambda f: f["saturation_e"])],
        ["DR (dB)", *both(lambda f: f["dr_db"])],
        ["SNR max (dB)", *both(lambda f: f["snr_max_db"])],
        ["linearity error (%)", *both(lambda f: f["linearity_error_pct"])],
        ["GSE (signal)", *both(lambda f: f["gse"])],
        ["dark current (e-/s)", *both(lambda f: f["dark_current_e_per_s"])],
        ["PRNU (%)", *both(lambda f: f["prnu_pct"])],
        [N.label("DSNU, model"), *both(lambda f: f["dsnu_V"] * 1e3)],
        ["DSNU, model / CG_out(0) (e-)", *both(lambda f: f["dsnu_e"])],
    ]


def build(ctx) -> Section:
    r = camera(ctx.design, steps=20 if ctx.quick else 50, backend=ctx.backend)
    s = summary(r)
    f1, f2 = ctx.figure("camera_ptc.png"), ctx.figure("camera_snr.png")
    ptc(r, f1)
    snr(r, f2)
    p = s["primary"]
    k_lsb = p["k_dn_per_e"] * p["lsb_V"]
    text = ["The designed pixel as a camera: an exposure series at 550 nm (each array at half its column "
            "swing at its own integration time), a 12-bit ADC over 1.2x the measured column swing, per-"
            "pixel mismatch from the device sizes and the layout grid. The figures are EMVA 1288's "
            "definitions applied to the model's mean and variance curves; `pixelkit camera --emva-out` "
            "writes the images, from which the emva1288 reference implementation recovers them "
            "(tests/test_camera.py). QE is per pixel area: the secondary's mask opening is its fill factor.",
            f"sigma_d (EMVA) and the read noise at the column are the same column noise referred to the "
            f"photodiode by two gains: K x LSB = {k_lsb * 1e6:.3f} uV/e- (the photon-transfer slope over 0 - 70 % "
            f"of saturation of the SPICE transfer, where C(V) has grown and the column compresses) and CG_out(0) = {p['cg_out_V_per_e'] * 1e6:.3f} uV/e- (zero "
            f"signal): {p['read_noise_chain_e']:.1f} e- x {p['cg_out_V_per_e'] * 1e6:.3f} / {k_lsb * 1e6:.3f} = "
            f"{p['read_noise_chain_e'] * p['cg_out_V_per_e'] / k_lsb:.1f} e- against sigma_d {p['read_noise_e']:.1f} "
            "e- (primary; the dark shot noise of the first exposure and rounding make the rest).",
            "DSNU, model counts only the TG channel charge's mismatch (half of it lands on FD); the DSNU, Monte "
            "Carlo of the section 'Sweeps, corners and Monte Carlo' draws every device in SPICE and is the figure "
            "to trust where the two differ.",
            "The photon-transfer and SNR plots end at saturation (the variance maximum): past it the signal clips, "
            "its variance collapses and an SNR computed from it rises without meaning; those exposures are marked "
            "x, not drawn as data."]
    flags = []
    for w in _ARR:
        f = s[w]
        if f["read_noise_e"] > plausibility.READ_NOISE_E:
            flags.append(f"{w} sigma_d (EMVA) {f['read_noise_e']:.0f} e-: the read noise flagged in the Noise "
                         "section, referred through K x LSB.")
        flag = plausibility.dsnu(w, f["dsnu_e"], "DSNU, model: TG channel-charge mismatch only, over CG_out(0)")
        if flag:
            flags.append(flag)
    return Section(TITLE, text=text, flags=flags,
                   tables=[Table("camera_emva", "EMVA 1288 figures", ["figure", "primary", "secondary"], _rows(s))],
                   figures=[Figure(f1.name, "Photon transfer up to saturation (x: clipped or variance below dark, "
                                            "not data)"),
                            Figure(f2.name, "SNR up to saturation (x: clipped exposures)")],
                   checked=[Checked(f"camera.{name}_{w}", s[w][k], u, tol_rel=0.03, note=note)
                            for w in _ARR
                            for name, k, u, note in (("k_dn_per_e", "k_dn_per_e", "DN/e-", "K"),
                                                     ("sigma_d_e", "read_noise_e", "e-", "sigma_d (EMVA)"),
                                                     ("dr_db", "dr_db", "dB", ""))],
                   data={"figures": s})
