"""``pixelkit sensor speed | rolling | lowgse | car``: the frame-level models."""
from __future__ import annotations

import click

from ..errors import ConfigError
from .common import design_arg, emit, json_opt, load, main, out_opt, output_path
from .types import FiniteRange

_TEST_POINT = (("c", "6 m", "m", "lateral distance camera - line of motion"),
               ("gamma", "44 deg", "rad", "angle of the image plane to the motion"),
               ("t-int", "53.6 ms", "s", "secondary exposure (trace duration)"),
               ("alpha", "7.4 deg", "rad", "angle of the trace start from the optical axis"),
               ("beta", "5 deg", "rad", "angle the trace subtends"),
               ("focal-length", "6 mm", "m", "focal length"),
               ("pixel", "3.75 um", "m", "pixel pitch"),
               ("dc", "0.15 m", "m", "uncertainty of c"))


def _quantity(opt: str, text: str, dim: str) -> float:
    from ..units import quantity
    return quantity(text, dim, f"--{opt}")


def _test_point_options(f):
    for name, default, _dim, help_text in reversed(_TEST_POINT):
        f = click.option(f"--{name}", default=default, show_default=True, help=help_text)(f)
    return click.option("--pixel-error-px", type=FiniteRange(0, 100), default=1.0, show_default=True,
                        help="angle uncertainty in pixels (the thesis [Thesis2019]: 1)")(f)


@main.group()
def sensor():
    """Frame-level models: double exposure, speed and its error budget, rolling-shutter distortion."""


@sensor.command()
@_test_point_options
@json_opt
def speed(pixel_error_px, as_json, **values):
    """Speed from a trace (eq. 2.1 - 2.5) and its error budget (eq. 2.6 - 2.11); thesis test point by default."""
    from ..sensor.speed import TracePoint, error_budget
    kw = {}
    for name, _default, dim, _h in _TEST_POINT:
        key = name.replace("-", "_")
        kw[key] = _quantity(name, values[key], dim)
    try:
        p = TracePoint(pixel_error_px=pixel_error_px, **kw)
    except ConfigError as exc:      # name the option and the value as written
        key = exc.field.replace("-", "_")
        opt = f"--{exc.field.replace('_', '-')}" if key in values else f"angle {exc.field} (--gamma, --alpha, --beta)"
        value = values.get(key, f"{exc.value:g} deg" if isinstance(exc.value, float) else exc.value)
        raise ConfigError("", opt, value, exc.allowed) from None
    r = error_budget(p)
    r["terms_kmh"] = {k: v * 3.6 for k, v in r["terms_ms"].items()}
    emit(r, as_json, lambda x: (f"v = {x['v_kmh']:.2f} km/h, dv = {x['dv_kmh']:.2f} km/h "
                                f"({100 * x['rel_err']:.2f} %); terms (km/h): "
                                + ", ".join(f"{k} {v:.3f}" for k, v in x["terms_kmh"].items())))


@sensor.command()
@click.option("--h", "h", type=FiniteRange(0.5, 2000), required=True, help="object height (rows)")
@click.option("--window", type=FiniteRange(0.5, 2000), required=True,
              help="accumulation window H = n rows (T_acc / T_row)")
@click.option("--speed", "s", type=FiniteRange(0, 0.95, min_open=True), required=True,
              help="object speed as a fraction of the scan speed (rows or columns per line time)")
@click.option("--direction", type=click.Choice(["down", "up", "right"]), required=True)
@click.option("--l", "l", type=FiniteRange(0.5, 2000), default=8.0, show_default=True,
              help="object width (columns)")
@out_opt("picture of the two sensors' images and the compensated one (PNG)")
@json_opt
def rolling(h, window, s, direction, l, out, as_json):
    """Rolling-shutter image of a moving rectangle vs the closed forms, and the two-sensor compensation."""
    from ..sensor.rolling_pair import study
    if (h + s * window) / (1 - s) > 4000 or l + s * (window + h) > 4000:
        raise ConfigError("", "--window", window, "a window and speed whose image fits in 4000 rows")
    r = study(h, window, s, direction, l)
    data = r["numbers"]
    if out:
        from ..sensor.pictures import rolling_pair
        data["picture"] = str(rolling_pair(r, out))
    keys = ("model_total_rows", "image_total_rows", "model_edge_rows", "image_edge_rows",
            "compensated_h_rows", "compensated_speed")
    emit(data, as_json, lambda x: "\n".join(f"{k:24s} {x[k]:.3f}" for k in keys))


@sensor.command()
@design_arg
@click.option("--speed", "speed_text", default="60 km/h", show_default=True, help="true speed of the car")
@click.option("--times", type=click.Choice(["sizing", "design"]), default="sizing", show_default=True,
              help="exposure times and mask opening: pixelkit's sizing (at the design's sizing level) or the design file's")
@click.option("--dc", "dc_text", default="0.15 m", show_default=True, help="uncertainty of the lateral distance")
@click.option("--seed", type=int, default=0, show_default=True, help="temporal noise seed")
@out_opt("picture: superposed, primary and secondary images with the trace (PNG; default reports/<design>/car.png)")
@json_opt
def car(design, speed_text, times, dc_text, seed, out, as_json):
    """Dual-pixel images of a passing car and the speed measured from its secondary trace."""
    from ..sensor import double_exposure as de
    v = _quantity("speed", speed_text, "m/s")
    if not 0 < v <= 100:
        raise ConfigError("", "--speed", speed_text, "a speed > 0 and <= 360 km/h")
    dc = _quantity("dc", dc_text, "m")
    if dc < 0:
        raise ConfigError("", "--dc", dc_text, "an uncertainty >= 0 m")
    d = load(design)
    r = de.measure(d, de.PassingCar(speed=v), de.exposure_times(d, times), dc=dc, seed=seed)
    from ..sensor.pictures import double_exposure
    r["picture"] = str(double_exposure(r, output_path(out, d, "car.png")))
    data = {k: x for k, x in r.items() if k != "images"}
    emit(data, as_json, lambda x: (f"measured {x['speed_kmh']:.2f} km/h (truth {x['truth_kmh']:.2f}, budget "
                                   f"+-{x['dv_kmh']:.2f}); trace {x['trace_px']:.2f} px "
                                   f"(truth {x['truth_trace_px']:.2f}); picture {x['picture']}"))


@sensor.command()
@click.option("--row", type=click.IntRange(0, 100000), default=500, show_default=True,
              help="row where the trace starts (eq. 2.18: row 500)")
@click.option("--row-length", type=click.IntRange(1, 100000), default=1650, show_default=True,
              help="pixel clocks per row, blanking included")
@click.option("--f-pixclk", "f_text", default="22 MHz", show_default=True, help="pixel clock")
@click.option("--gse", type=FiniteRange(1, 1e9), default=310.0, show_default=True,
              help="global shutter efficiency eta_pd / eta_mem")
@click.option("--t-int", "t_text", default="0.2 ms", show_default=True, help="exposure the thesis set")
@out_opt("picture: sharpness, trace contrast and their product against t_int / (t_wait / GSE) (PNG)")
@json_opt
def lowgse(row, row_length, f_text, gse, t_text, out, as_json):
    """Low-GSE emulation of the double exposure: the rule t_int ~ t_readout / GSE and why it matters."""
    from ..sensor import lowgse as lg
    f = _quantity("f-pixclk", f_text, "Hz")
    t_int = _quantity("t-int", t_text, "s")
    if not f > 0:
        raise ConfigError("", "--f-pixclk", f_text, "a clock > 0 Hz")
    if not t_int > 0:
        raise ConfigError("", "--t-int", t_text, "an exposure > 0 s")
    cam = lg.Camera(n_rows=max(960, row + 1), row_length=row_length, f_pixclk=f, gse=gse)
    rule = lg.rule_of_thumb(cam, row)
    scene = lg.StreetScene(first_row=max(0, row - lg.StreetScene.rows // 2))
    b = lg.balance(cam, scene)
    tr = lg.trace_speed(cam, scene, t_int)
    data = {"t_rule_s": rule, "t_int_s": t_int, "t_int_over_rule": t_int / rule, "t_wait_s": cam.t_wait(row),
            "best_ratio_image": b["best_ratio"], "sweep": b["sweep"], "trace_speed": tr}
    if out:
        from ..sensor.pictures import balance
        data["picture"] = str(balance(b, out))
    emit(data, as_json, lambda x: (f"rule of thumb t_int ~ t_wait / GSE = {x['t_rule_s'] * 1e3:.4g} ms; set "
                                   f"{x['t_int_s'] * 1e3:.4g} ms = {x['t_int_over_rule']:.2f} x rule; the image's "
                                   f"sharpness x trace contrast peaks at t_int = {x['best_ratio_image']:g} x rule; "
                                   f"trace "
                                   f"{x['trace_speed']['trace_px']:.2f} px (truth {x['trace_speed']['truth_px']:.2f}), "
                                   f"v = d / t_wait = {x['trace_speed']['speed_px_s']:.0f} px/s "
                                   f"(truth {x['trace_speed']['truth_speed_px_s']:.0f})"))
