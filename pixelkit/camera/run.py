"""The virtual camera of a design: both arrays' EMVA 1288 figures, curves, noise budget, datasets."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..physics import fd
from .afe_spicenoise import afe_output_noise
from .emva_export import check_target, write_dataset
from .figures import emva_figures
from .mismatch import draw
from .model import ARRAYS, array_camera
from .ptc import analytic, series
from .spicenoise import output_cg, pixel_noise, sf_gain
from .transfer import spice_transfer


def array_report(design, which: str, a_sf: float, transfer: dict, seed: int, steps: int = 50,
                 shape: tuple | None = None) -> dict:
    cam = array_camera(design, which, a_sf, transfer, shape=shape)
    s = series(cam, steps)
    cur = analytic(cam, s)
    fig = emva_figures(cur["mu_p"], cur["mean_dn"], cur["var_dn"], cur["dark_mean_dn"], cur["dark_var_dn"])
    mm = draw(design, which, a_sf, (cam.rows, cam.cols), seed)
    sig_e = (cur["mean_dn"] - cur["dark_mean_dn"]) / fig["k_dn_per_e"]
    noise_e = np.sqrt(np.maximum(cur["var_dn"], 0.0)) / fig["k_dn_per_e"]
    ch = cam.chain
    return {
        "camera": cam, "series": s, "mismatch": mm, "curves": cur,
        "figures": {**fig, "gse": fd.signal_gse(design, which, a_sf),
                    "k0_dn_per_e": cam.k0_dn_per_e, "cg_out_V_per_e": cam.cg0_V_per_e,
                    "read_noise_chain_e": ch["pixel_e"], "read_noise_afe_e": ch["afe_e"],
                    "dark_current_e_per_s": cam.dark_e_per_s, "prnu_pct": 100 * mm.sigma_gain,
                    "dsnu_V": mm.sigma_offset_V, "dsnu_e": mm.sigma_offset_V / cam.cg0_V_per_e, "bits": cam.adc.bits,
                    "lsb_V": cam.adc.lsb_V, "clip_V": cam.clip_V, "a_sf": a_sf,
                    "wavelength_m": cam.wavelength_m, "irradiance_W_m2": s.irradiance_W_m2,
                    "t_int_s": cam.t_int},
        "snr": {"mu_p": s.mu_p.tolist(), "snr": (sig_e / noise_e).tolist()},
        "noise_e": ch["electrons"],
    }


def camera(design, seed: int = 1, emva_out: str | Path | None = None, steps: int = 50,
           shape: tuple | None = None, backend: str = "batch") -> dict:
    """Both arrays, on the pixel's SPICE transfer (``camera.transfer``); ``shape``: image size
    of the virtual sensor (default: each array's own)."""
    if emva_out is not None:      # refuse a bad target before anything runs or is written
        for which in ARRAYS:
            check_target(Path(emva_out) / which)
    a_sf = sf_gain(design)
    transfer = spice_transfer(design, backend)
    out = {which: array_report(design, which, a_sf, transfer, seed, steps, shape) for which in ARRAYS}
    cg = output_cg(design, backend=backend)
    afe_in = afe_output_noise(design)["total_V2"] * (design.afe.c13 / design.afe.c11) ** 2
    for which in ARRAYS:   # the independent SPICE figures beside the analytic ones
        sp = pixel_noise(design, which, a_sf)
        f = out[which]["figures"]
        f["cg_out_spice_V_per_e"] = cg[which]
        f["read_noise_spice_e"] = sp["pixel_V"] / f["cg_out_V_per_e"]
        f["read_noise_afe_spice_e"] = np.sqrt(sp["pixel_V"] ** 2 + afe_in) / f["cg_out_V_per_e"]
    if emva_out is not None:
        for which in ARRAYS:
            r = out[which]
            r["dataset"] = str(write_dataset(Path(emva_out) / which, r["camera"], r["series"], r["mismatch"], seed))
    return out


def summary(result: dict) -> dict:
    """JSON-ready figures: ``{array: {figure: value}}`` plus the noise budget and datasets."""
    out = {}
    for which, r in result.items():
        out[which] = {**{k: float(v) if not isinstance(v, int) else v for k, v in r["figures"].items()},
                      "noise_budget_e": r["noise_e"]}
        if "dataset" in r:
            out[which]["dataset"] = r["dataset"]
    return out
