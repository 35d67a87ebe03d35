"""Plain-text renderings of the figures the CLI prints (units converted at this edge)."""
from __future__ import annotations


def _row(label, *cells):
    return f"  {label:<34}" + "".join(f"{c:>14}" for c in cells)


def model_text(t: dict) -> str:
    p, s = t["primary"], t["secondary"]
    lines = [f"Analytic models: {t['design']} ({t['technology']}, C_jdep at V_R = {t['reset_bias_V']:g} V)",
             _row("", "primary", "secondary"),
             _row("PD area (um2)", f"{p['area_m2'] * 1e12:.2f}", f"{s['area_m2'] * 1e12:.2f}"),
             _row("PD perimeter (um)", f"{p['perimeter_m'] * 1e6:.2f}", f"{s['perimeter_m'] * 1e6:.2f}"),
             _row("photoactive area (um2)", f"{p['photoactive_area_m2'] * 1e12:.3f}",
                  f"{s['photoactive_area_m2'] * 1e12:.3f}"),
             _row("C_jdep (fF)", f"{p['c_jdep_F'] * 1e15:.2f}", f"{s['c_jdep_F'] * 1e15:.2f}"),
             _row("PD node incl. EC/TG (fF)", f"{p['c_node_F'] * 1e15:.2f}", f"{s['c_node_F'] * 1e15:.2f}"),
             _row("conversion gain (uV/e-)", f"{p['cg_V_per_e'] * 1e6:.2f}", f"{s['cg_V_per_e'] * 1e6:.2f}"),
             _row("full well, swing x C (ke-)", f"{p['fwc_e'] / 1e3:.1f}", f"{s['fwc_e'] / 1e3:.1f}"),
             _row("full well with C(V) (ke-)", f"{p['fwc_cv_e'] / 1e3:.1f}", f"{s['fwc_cv_e'] / 1e3:.1f}"),
             _row("dark current (fA)", f"{p['dark_current_A'] * 1e15:.3f}", f"{s['dark_current_A'] * 1e15:.3f}"),
             f"  C_A = A1/A2 = {t['c_a']:.3f}   C_C = C_jdep1/C_jdep2 = {t['c_c']:.3f}   "
             f"photoactive ratio = {t['photoactive_ratio']:.1f}"]
    return "\n".join(lines)


def simulate_text(r: dict) -> str:
    p, s, m = r["primary"], r["secondary"], r["model_vs_spice"]
    lines = [f"Simulation experiment (fig. A.1 - A.3): exposure window {r['t_window_s'] * 1e6:g} us, "
             f"backend {r['backend']}, ngspice {r['ngspice_version']}",
             _row("", "primary", "secondary"),
             _row("output swing at the column (mV)", f"{p['swing_V'] * 1e3:.0f}", f"{s['swing_V'] * 1e3:.0f}"),
             _row("target (fraction of swing)", f"{p['target_frac']:.2f}", f"{s['target_frac']:.2f}"),
             _row("photocurrent at target (pA)", f"{p['i_mid_A'] * 1e12:.1f}", f"{s['i_5pct_A'] * 1e12:.1f}"),
             f"  i_mid / i_5pct = {r['ratio']:.1f} (thesis 1400 / 52 = 26.9; linear ideal "
             f"{r['ratio_ideal']:.1f})",
             f"  fig. A.1 (currents in ratio C_C): worst difference {r['fig_a1']['max_diff_frac'] * 100:.2f} % of swing",
             f"  analytic model vs SPICE over 10-90 % of swing: worst {m['max_err_frac'] * 100:.2f} %",
             f"  {r['n_runs']} SPICE runs ({r['n_cached']} from cache) in {r['wall_s']:.1f} s"]
    return "\n".join(lines)


def size_text(r: dict) -> str:
    a, s, v = r["levels"]["analytic"], r["levels"]["spice"], r["verify"]
    lines = [f"Sizing ({r['level']} level chosen); sized design: {r['sized_design']}",
             _row("", "analytic", "SPICE curves"),
             _row("C_M", f"{a['c_m']:.1f}", f"{s['c_m']:.1f}"),
             _row("mask opening (um2)", f"{a['mask_open_m2'] * 1e12:.3f}", f"{s['mask_open_m2'] * 1e12:.3f}"),
             _row("t_int primary (us)", f"{a['t_int_primary_s'] * 1e6:.1f}", f"{s['t_int_primary_s'] * 1e6:.1f}"),
             _row("t_int secondary (us)", f"{a['t_int_secondary_s'] * 1e6:.1f}",
                  f"{s['t_int_secondary_s'] * 1e6:.1f}"),
             _row("trace at speed_min (px)", f"{a['trace_px_at_speed_min']:.1f}", f"{s['trace_px_at_speed_min']:.1f}"),
             _row("primary motion (px)", f"{a['motion_px_primary']:.2f}", f"{s['motion_px_primary']:.2f}"),
             f"  verify in SPICE: primary at {v['primary_frac'] * 100:.1f} % of swing, "
             f"secondary at {v['secondary_frac'] * 100:.1f} %",
             f"  analytic solve {r['solve_time_s'] * 1e3:.1f} ms",
             f"  why the levels differ: {r['why_levels_differ']}"]
    for row in r.get("sensitivity", []):
        lines.append(f"  {row['variant']:<22} C_M {row['c_m']:6.1f} ({row['c_m_change_frac'] * 100:+5.1f} %)  "
                     f"t_p {row['t_int_primary_s'] * 1e6:7.1f} us ({row['t_primary_change_frac'] * 100:+5.1f} %)")
    return "\n".join(lines)
