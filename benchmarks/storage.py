"""Long-exposure decks: the real 1 ms / 12 ms integration against the short-window bench.

The real-timing deck steps the flat exposure with the simulator's error control (max step
t_row / 2, edges as PWL breakpoints); a 20 ns max step over 12 ms would take 600 000
steps. Reported: wall time of each deck, of the same deck at t_row / 20, the ratios, and
the double-sampled signals of the decks delivering the same charge (they should agree).

    python3 benchmarks/storage.py
"""
from __future__ import annotations

import time
from dataclasses import replace

from common import reference_design
from pixelkit.circuits.testbench import dual_pixel_bench, real_timings, timings
from pixelkit.measure.pixel import double_sampled
from pixelkit.spice import simulate


def measure(d) -> dict:
    i_p, i_s = 20e-12, 0.5e-12
    tw = d.experiment.t_window
    t0 = time.perf_counter()
    short = simulate(dual_pixel_bench(d, i_p * d.primary.t_int / tw, i_s * d.secondary.t_int / tw,
                                      title="bench_short"), use_cache=False)
    t_short = time.perf_counter() - t0
    tm = real_timings(d)
    t0 = time.perf_counter()
    long = simulate(dual_pixel_bench(d, i_p, i_s, title="bench_long", tm=tm), use_cache=False)
    t_long = time.perf_counter() - t0
    net = dual_pixel_bench(d, i_p, i_s, title="bench_fine", tm=tm)
    fine = replace(net, analysis=replace(net.analysis, max_step=net.analysis.max_step / 10))
    t0 = time.perf_counter()
    fine = simulate(fine, use_cache=False)
    t_fine = time.perf_counter() - t0
    ts = timings(d, tw)
    return {"short_s": t_short, "long_s": t_long, "fine_s": t_fine, "points_long": int(long.time.size),
            "signal_fine_V": (double_sampled(fine, "col_p", tm["primary"]), double_sampled(fine, "col_s0", tm["secondary"])),
            "signal_short_V": (double_sampled(short, "col_p", ts["primary"]), double_sampled(short, "col_s0", ts["secondary"])),
            "signal_long_V": (double_sampled(long, "col_p", tm["primary"]), double_sampled(long, "col_s0", tm["secondary"]))}


def main():
    r = measure(reference_design())
    print(f"short-window bench, same charge (baseline): {r['short_s']:7.2f} s")
    print(f"real 1 ms / 12 ms bench ({r['points_long']} points):  {r['long_s']:7.2f} s  "
          f"{r['long_s'] / r['short_s']:5.1f} x baseline")
    print(f"the same at a 10x smaller max step:           {r['fine_s']:7.2f} s  "
          f"{r['fine_s'] / r['short_s']:5.1f} x baseline")
    print("signals (primary, secondary) V: short %.4f %.4f, real %.4f %.4f, real fine step %.4f %.4f"
          % (*r["signal_short_V"], *r["signal_long_V"], *r["signal_fine_V"]))


if __name__ == "__main__":
    main()
