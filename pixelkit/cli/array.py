"""``pixelkit array``: an array read row by row (fig. 3.13)."""
from __future__ import annotations

import click

from .common import design_arg, emit, json_opt, load, main, out_opt, output_path, spice_opts, waveforms_opt


@main.command("array")
@design_arg
@click.option("--rows", type=click.IntRange(1, 27), default=2, show_default=True)
@click.option("--cols", type=click.IntRange(1, 50), default=2, show_default=True)
@out_opt("PNG of the readout waveforms (default: reports/<design>/array_RxC.png)")
@spice_opts
@waveforms_opt
@json_opt
def array_cmd(design, rows, cols, out, backend, jobs, waveforms, as_json):
    """Simulate an array read row by row (fig. 3.13); one photocurrent per subpixel."""
    from ..api import simulate, write_waveforms
    from ..circuits.testbench import array_bench, timings
    from ..measure.pixel import double_sampled
    from ..plots.waveforms import plot_columns
    d = load(design)
    n = d.secondary_per_pixel
    # distinct photocurrents so that every subpixel is told apart (as in fig. 3.13)
    ip = [[0.2e-9 * (1 + r * cols + c) for c in range(cols)] for r in range(rows)]
    is_ = [[10e-12 * (1 + r * n * cols + j) for j in range(n * cols)] for r in range(rows)]
    net = array_bench(d, rows, cols, ip, is_)
    net.meta["what"] = f"{rows} x {cols} array bench of {d.name}"
    res = simulate(net, backend=backend)
    tm = timings(d, d.experiment.t_window, rows)
    data = {"rows": rows, "cols": cols,
            "primary_signal_V": [[double_sampled(res, f"col_p_{c}", tm["primary"], r) for c in range(cols)]
                                 for r in range(rows)],
            "secondary_signal_V": [[double_sampled(res, f"col_s_{j}", tm["secondary"], r)
                                    for j in range(n * cols)] for r in range(rows)],
            "iph_primary_A": ip, "iph_secondary_A": is_}
    cols_p = [f"col_p_{c}" for c in range(cols)]
    cols_s = [f"col_s_{j}" for j in range(n * cols)]
    data["plot"] = str(plot_columns(res, {"primary": cols_p, "secondary": cols_s},
                                    output_path(out, d, f"array_{rows}x{cols}.png"),
                                    f"{d.name}: {rows} x {cols} readout (after SF, before AFE)"))
    if waveforms:
        data["waveforms"] = str(write_waveforms(res, waveforms))
    emit(data, as_json, lambda x: "\n".join([f"plot: {x['plot']}"] + [
        f"row {r}: primary {[round(v * 1e3, 1) for v in x['primary_signal_V'][r]]} mV, "
        f"secondary {[round(v * 1e3, 1) for v in x['secondary_signal_V'][r]]} mV" for r in range(x["rows"])]
        + ([f"waveforms: {x['waveforms']}"] if waveforms else [])))
