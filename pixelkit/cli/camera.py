"""``pixelkit camera``: the designed pixel as a virtual camera with its EMVA 1288 figures."""
from __future__ import annotations

import click

from .common import design_arg, emit, json_opt, load, main, out_opt, output_path, spice_opts

_ROWS = (("K (DN/e-)", "k_dn_per_e", 1.0, ".4g"), ("CG out (uV/e-)", "cg_out_V_per_e", 1e6, ".3f"),
         ("CG out, SPICE step (uV/e-)", "cg_out_spice_V_per_e", 1e6, ".3f"),
         ("read noise, EMVA (e-)", "read_noise_e", 1.0, ".1f"),
         ("read noise, chain (e-)", "read_noise_chain_no_dark_e", 1.0, ".1f"),
         ("read noise, SPICE (e-)", "read_noise_spice_e", 1.0, ".1f"),
         ("read noise, AFE probe (e-)", "read_noise_afe_e", 1.0, ".1f"),
         ("read noise, AFE, SPICE (e-)", "read_noise_afe_spice_e", 1.0, ".1f"),
         ("QE (EMVA eta)", "qe", 1.0, ".4g"), ("saturation (e-)", "saturation_e", 1.0, ".0f"),
         ("DR (dB)", "dr_db", 1.0, ".1f"), ("SNR max (dB)", "snr_max_db", 1.0, ".1f"),
         ("linearity error (%)", "linearity_error_pct", 1.0, ".2f"), ("GSE (signal)", "gse", 1.0, ".1f"),
         ("dark current (e-/s)", "dark_current_e_per_s", 1.0, ".1f"), ("PRNU (%)", "prnu_pct", 1.0, ".3f"),
         ("DSNU (e-)", "dsnu_e", 1.0, ".0f"))


def camera_text(r: dict) -> str:
    p, s = r["primary"], r["secondary"]
    lines = [f"{'':26s}{'primary':>14s}{'secondary':>14s}"]
    for label, key, scale, spec in _ROWS:
        lines.append(f"{label:26s}{p[key] * scale:>14{spec}}{s[key] * scale:>14{spec}}")
    lines.append("read-noise budget (e- rms): " + ", ".join(
        f"{k} {p['noise_budget_e'][k]:.0f} / {s['noise_budget_e'][k]:.0f}" for k in p["noise_budget_e"]))
    lines += [f"plot: {f}" for f in r.get("plots", [])]
    lines += [f"dataset: {x['dataset']}" for x in (p, s) if "dataset" in x]
    return "\n".join(lines)


@main.command()
@design_arg
@out_opt("folder for the plots (default: reports/<design>/camera)", folder=True)
@click.option("--emva-out", type=click.Path(file_okay=False), default=None,
              help="write the exposure series as EMVA 1288 datasets: DIR/primary, DIR/secondary")
@click.option("--seed", type=click.IntRange(0, 2 ** 31 - 1), default=1, show_default=True,
              help="seed of the per-pixel mismatch and the temporal noise")
@click.option("--size", "size", default=None, metavar="ROWSxCOLS",
              help="image size of the virtual sensor (default: each array's own)")
@spice_opts
@json_opt
def camera(design, out, emva_out, seed, size, backend, jobs, as_json):
    """EMVA 1288 figures of both arrays (K, read noise, QE, saturation, DR, SNR, GSE), plots, datasets."""
    from ..camera.plots import write_all
    from ..camera.run import camera as run, summary
    from ..errors import ConfigError
    from ..fileio import check_output
    shape = None
    if size is not None:
        try:
            shape = tuple(int(x) for x in size.lower().split("x"))
        except ValueError:
            shape = ()
        if len(shape) != 2 or not all(8 <= x <= 4096 for x in shape):
            raise ConfigError("--size", "size", size, "ROWSxCOLS with 8 .. 4096 each, e.g. 128x128")
    d = load(design)
    if emva_out is not None:
        check_output(emva_out)
    r = run(d, seed=seed, emva_out=emva_out, shape=shape, backend=backend)
    data = summary(r)
    data["plots"] = write_all(r, output_path(out, d, "camera"))
    data["design"] = d.name
    emit(data, as_json, camera_text)
