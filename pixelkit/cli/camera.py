"""``pixelkit camera``: the designed pixel as a virtual camera with its EMVA 1288 figures."""
from __future__ import annotations

import click

from .types import FilePath

from .common import design_arg, emit, json_opt, load, main, out_opt, output_path, spice_opts, post_layout_opt

_ROWS = (("K (DN/e-)", "k_dn_per_e", 1.0, ".4g"),
         ("K x LSB (uV/e-)", None, 1e6, "sig"),
         ("CG_out(0), model (uV/e-)", "cg_out_V_per_e", 1e6, "sig"),
         ("CG_out(0), SPICE step (uV/e-)", "cg_out_spice_V_per_e", 1e6, "sig"),
         ("QE (EMVA eta)", "qe", 1.0, ".4g"), ("mu_e.sat (EMVA) (e-)", "saturation_e", 1.0, ".0f"),
         ("DR (dB)", "dr_db", 1.0, ".1f"), ("SNR max (dB)", "snr_max_db", 1.0, ".1f"),
         ("linearity error (%)", "linearity_error_pct", 1.0, ".2f"), ("GSE (signal)", "gse", 1.0, ".1f"),
         ("dark current (e-/s)", "dark_current_e_per_s", 1.0, ".1f"), ("PRNU (%)", "prnu_pct", 1.0, ".3f"))

#: The read-noise figures: (label, key, what it is). Each is a temporal noise in e- rms; they differ by
#: what they include and by the gain that refers them to the photodiode.
_NOISE = (("sigma_d (EMVA)", "read_noise_e", "dark temporal noise of the images / K"),
          ("at the column, model", "read_noise_chain_e", "pixel chain (NCDS) / CG_out(0)"),
          ("at the column, SPICE", "read_noise_spice_e", "ngspice .noise of the chain / CG_out(0)"),
          ("with the AFE, model", "read_noise_afe_e", "+ the SC AFE / CG_out(0)"),
          ("with the AFE, SPICE", "read_noise_afe_spice_e", "+ the AFE, .noise / CG_out(0)"))


def _value(f: dict, key):
    return f["k_dn_per_e"] * f["lsb_V"] if key is None else f[key]


def camera_text(r: dict) -> str:
    p, s = r["primary"], r["secondary"]
    lines = [f"{'':30s}{'primary':>12s}{'secondary':>12s}"]
    from ..report.html import fmt

    def cell(x, spec):   # "sig": 4 significant digits, as the report prints them
        return fmt(float(x)) if spec == "sig" else format(x, spec)
    for label, key, scale, spec in _ROWS:
        lines.append(f"{label:30s}{cell(_value(p, key) * scale, spec):>12}{cell(_value(s, key) * scale, spec):>12}")
    lines.append("read noise (e- rms), each with what it includes and the gain that refers it:")
    for label, key, what in _NOISE:
        lines.append(f"  {label:28s}{p[key]:>12.1f}{s[key]:>12.1f}   {what}")
    k_lsb = _value(p, None)
    lines.append(f"  (sigma_d = column noise / K x LSB: {p['read_noise_chain_e']:.1f} x "
                 f"{p['cg_out_V_per_e'] * 1e6:.3f} / {k_lsb * 1e6:.3f} = "
                 f"{p['read_noise_chain_e'] * p['cg_out_V_per_e'] / k_lsb:.1f} e- for the primary)")
    lines.append(f"DSNU, model (TG channel-charge mismatch only): {p['dsnu_V'] * 1e3:.2f} / "
                 f"{s['dsnu_V'] * 1e3:.2f} mV = {p['dsnu_e']:.0f} / {s['dsnu_e']:.0f} e- "
                 "(pixelkit mc draws every device's mismatch in SPICE)")
    lines.append("read-noise budget (e- rms): " + ", ".join(
        f"{k} {p['noise_budget_e'][k]:.0f} / {s['noise_budget_e'][k]:.0f}" for k in p["noise_budget_e"]))
    lines += [f"plot: {f}" for f in r.get("plots", [])]
    lines += [f"dataset: {x['dataset']}" for x in (p, s) if "dataset" in x]
    return "\n".join(lines)


@main.command()
@design_arg
@out_opt("folder for the plots (default: reports/<design>/camera)", folder=True)
@click.option("--emva-out", type=FilePath(file_okay=False), default=None,
              help="write the exposure series as EMVA 1288 datasets: DIR/primary, DIR/secondary")
@click.option("--seed", type=click.IntRange(0, 2 ** 31 - 1), default=1, show_default=True,
              help="seed of the per-pixel mismatch and the temporal noise")
@click.option("--size", "size", default=None, metavar="ROWSxCOLS",
              help="image size of the virtual sensor (default: each array's own)")
@spice_opts
@post_layout_opt
@json_opt
def camera(design, out, emva_out, seed, size, backend, jobs, as_json):
    """EMVA 1288 figures of both arrays (K, read noise, QE, saturation, DR, SNR, GSE), plots, datasets."""
    from ..camera.plots import write_all
    from ..camera.run import camera as run, summary
    from ..errors import ConfigError
    from ..fileio import check_output
    from ..spice.counter import spice_progress
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
    with spice_progress("camera") as bar:
        r = run(d, seed=seed, emva_out=emva_out, shape=shape, backend=backend)
        data = summary(r)
        bar.set_description("camera: plots")
        data["plots"] = write_all(r, output_path(out, d, "camera"))
    data["design"] = d.name
    emit(data, as_json, camera_text)
