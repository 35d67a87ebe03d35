"""Frame-level models: the design's passing car; for the reference chip, the frame models' validation.

Independent paths: the time-stepped exposure of ``pixelkit.sensor.exposure`` (every image
here), the scene's true speed, and the printed test point of [Thesis2019]. The passing car
uses the design's optics, scene, apertures and pixelkit's sizing (it needs ``[optics]`` and
``[scene]`` in the design file). The speed budget at the dissertation's test point, the
low-GSE balance on its MT9M021 set-up and the rolling-shutter cases of [Rychazhnikov2008a] /
[Rychazhnikov2008b] do not depend on the design: they validate the kit's frame models and
appear in the report of the reference chip only (``ctx.reference``).
"""
from __future__ import annotations

from . import Checked, Figure, Section, Table

TITLE = "Frame-level models"

ROLLING_CASES = ((12.0, 60.0, 0.5, "down"), (12.0, 60.0, 0.5, "up"), (20.0, 8.0, 0.3, "up"),
                 (12.0, 60.0, 0.5, "right"))


def _speed_rows():
    from ...sensor.speed import TracePoint, error_budget
    b = error_budget(TracePoint())
    rows = [[k, abs(v) * 3.6] for k, v in b["terms_ms"].items()]
    return b, rows + [["total (root sum of squares)", b["dv_kmh"]]]


def _rolling(ctx, quick):
    from ...sensor.pictures import rolling_pair
    from ...sensor.rolling_pair import study
    rows, figs = [], []
    for h, window, s, d in (ROLLING_CASES[:2] + ROLLING_CASES[3:]) if quick else ROLLING_CASES:
        r = study(h, window, s, d, l=10.0)
        n = r["numbers"]
        pub = n["published"]
        figures = [("base angle (deg)", "base_angle_deg")] if d == "right" else \
            [("total rows", "total_rows"), ("edge rows", "edge_rows")]
        for label, key in figures:
            rows.append([d, h, window, s, label, float(n[f"model_{key}"]), float(n[f"image_{key}"]),
                         float(pub[key]), float(n["compensated_h_rows"])])
        if d in ("up", "right") and window == 60.0:
            path = rolling_pair(r, ctx.figure(f"frame_rolling_{d}.png"))
            figs.append(Figure(path.name, f"Moving {d}: the down- and up-scanning sensors' images and the "
                                          "compensated image (sideways: with the global-shutter reference)"))
    return rows, figs


def _validation(ctx, figs: list, tables: list, checked: list, text: list) -> dict:
    """The frame models against the dissertation's test point and the rolling-shutter papers."""
    from ...sensor import lowgse as lg
    from ...sensor.pictures import balance
    quick = ctx.quick
    ctx.progress("frame: speed budget")
    b, speed_rows = _speed_rows()
    ctx.progress("frame: rolling shutter")
    rolling_rows, rolling_figs = _rolling(ctx, quick)
    figs += rolling_figs
    ctx.progress("frame: low-GSE balance")
    bal = lg.balance(ratios=(0.25, 1.0, 4.0) if quick else (0.125, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0))
    path = balance(bal, ctx.figure("frame_lowgse_balance.png"))
    figs.append(Figure(path.name, "Low-GSE emulation: scene sharpness and trace contrast measured on the image "
                                  "against t_int / (t_wait / GSE), and the emulated image at the rule"))
    tables += [Table("frame_speed_budget", "Speed error budget at the test point of [Thesis2019] (km/h)",
                     ["term", "contribution (km/h)"], speed_rows),
               Table("frame_rolling", "Rolling shutter: kit's closed form, image simulation, published form",
                     ["direction", "h (rows)", "H (rows)", "s (v/v_H)", "figure", "kit", "image", "published",
                      "compensated h (rows)"], rolling_rows)]
    checked += [Checked("frame.dv_kmh", b["dv_kmh"], "km/h", tol_rel=0.01),
                Checked("frame.lowgse_best_ratio", bal["best_ratio"], "1", tol_rel=0.01)]
    text += ["This design is the test chip of [Thesis2019], so the report also validates the kit's frame models "
             "against the dissertation and the rolling-shutter papers (they do not depend on the design).",
             f"Speed from a trace at the test point of [Thesis2019]: v = {b['v_kmh']:.2f} km/h, dv = "
             f"{b['dv_kmh']:.2f} km/h ({100 * b['rel_err']:.2f} %); the dissertation prints 1.3 km/h and 2.5 % "
             "(its dc term alone: 2.50 %).",
             f"Low-GSE emulation: the rule t_int ~ t_wait / GSE gives {bal['t_rule_s'] * 1e3:.3g} ms at row 500 "
             f"(MT9M021, 1650 clocks per row, 22 MHz, GSE 310); on the simulated image the product of scene "
             f"sharpness and trace contrast peaks at t_int = {bal['best_ratio']:g} x the rule.",
             "Rolling shutter: every image is a time-stepped exposure; the kit's closed forms follow it within one "
             "pixel, the published forms of [Rychazhnikov2008a] / [Rychazhnikov2008b] fail where the table's last "
             "columns differ."]
    return {"lowgse_sweep": bal["sweep"]}


def _passing_car(ctx, figs: list, tables: list, checked: list) -> None:
    from ...sensor import double_exposure as de
    from ...sensor.pictures import double_exposure
    ctx.progress("frame: passing car")
    times = ctx.shared("frame_times", lambda: de.exposure_times(ctx.design, "sizing"))
    car_rows = []
    for kmh in (60.0,) if ctx.quick else (40.0, 60.0, 90.0, 130.0):
        r = de.measure(ctx.design, de.PassingCar(speed=kmh / 3.6), times)
        car_rows.append([kmh] + [float(r[k]) for k in ("speed_kmh", "dv_kmh", "trace_px", "truth_trace_px")])
        if kmh == 60.0:
            path = double_exposure(r, ctx.figure("frame_car.png"))
            figs.insert(0, Figure(path.name, "Passing car at 60 km/h: superposed image, primary array, secondary "
                                             "array with the extracted trace"))
            checked.append(Checked("frame.car_speed_60_kmh", float(r["speed_kmh"]), "km/h", tol_abs=0.5))
    tables.insert(0, Table("frame_car", f"Speed from the simulated secondary image ({times['source']}: "
                                        f"t_p = {times['t_primary_s'] * 1e3:.3g} ms, "
                                        f"t_s = {times['t_secondary_s'] * 1e3:.3g} ms)",
                           ["truth (km/h)", "measured (km/h)", "budget dv (km/h)", "trace (px)", "true trace (px)"],
                           car_rows))


def build(ctx) -> Section:
    d = ctx.design
    has_scene = d.optics is not None and d.scene is not None
    if not has_scene and not ctx.reference:
        return Section.needs_input(TITLE, "[optics] and [scene] in the design file",
                                   "the passing-car images need the design's lens and measurement scene")
    figs, tables, checked, text, data = [], [], [], [], {}
    if has_scene:
        _passing_car(ctx, figs, tables, checked)
        text.append("A car passes the design's scene: its double-exposure images are simulated with the design's "
                    "optics, apertures and sized integration times, and the speed is measured from the secondary "
                    "array's trace.")
    else:
        text.append("The design has no [optics] / [scene] table: the passing-car images are not drawn.")
    if ctx.reference:
        data = _validation(ctx, figs, tables, checked, text)
    return Section(TITLE, text=text, tables=tables, figures=figs, checked=checked, data=data)
