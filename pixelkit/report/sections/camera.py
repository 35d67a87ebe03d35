"""Virtual camera section: EMVA 1288 figures of both arrays, photon transfer and SNR curves."""
from __future__ import annotations

from ...camera.plots import ptc, snr
from ...camera.run import camera, summary
from . import Checked, Figure, Section, Table

TITLE = "Virtual camera: EMVA 1288 figures"
_ROWS = (("K (DN/e-)", "k_dn_per_e"), ("read noise (e-)", "read_noise_e"), ("QE eta", "qe"),
         ("saturation (e-)", "saturation_e"), ("DR (dB)", "dr_db"), ("SNR max (dB)", "snr_max_db"),
         ("linearity error (%)", "linearity_error_pct"), ("GSE (signal)", "gse"),
         ("dark current (e-/s)", "dark_current_e_per_s"), ("PRNU (%)", "prnu_pct"), ("DSNU (e-)", "dsnu_e"))


def build(ctx) -> Section:
    e = ctx.experiment()
    swings = {w: e[w]["swing_V"] for w in ("primary", "secondary")}
    r = camera(ctx.design, swings=swings, steps=20 if ctx.quick else 50, backend=ctx.backend)
    s = summary(r)
    f1, f2 = ctx.figure("camera_ptc.png"), ctx.figure("camera_snr.png")
    ptc(r, f1)
    snr(r, f2)
    rows = [[label, s["primary"][k], s["secondary"][k]] for label, k in _ROWS]
    text = ["The designed pixel as a camera: an exposure series at 550 nm (each array at half its column "
            "swing at its own integration time), a 12-bit ADC over 1.2x the measured column swing, per-"
            "pixel mismatch from the device sizes and the layout grid. The figures are EMVA 1288's "
            "definitions applied to the model's mean and variance curves; `pixelkit camera --emva-out` "
            "writes the images, from which the emva1288 reference implementation recovers them "
            "(tests/test_camera.py). QE is per pixel area: the secondary's mask opening is its fill factor."]
    return Section(TITLE, text=text,
                   tables=[Table("camera_emva", "EMVA 1288 figures", ["figure", "primary", "secondary"], rows)],
                   figures=[Figure(f1.name, "Photon transfer"), Figure(f2.name, "SNR")],
                   checked=[Checked(f"camera.{k}_{w}", s[w][k], u, tol_rel=0.03)
                            for w in ("primary", "secondary")
                            for k, u in (("k_dn_per_e", "DN/e-"), ("read_noise_e", "e-"), ("dr_db", "dB"))],
                   data={"figures": s})
