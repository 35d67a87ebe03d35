"""Plain-text renderings of the figures the CLI prints (units converted at this edge)."""
from __future__ import annotations

import math


def _row(label, *cells):
    return f"  {label:<44}" + "".join(f"{c:>12}" for c in cells)


def _cell(x: float, fm: str) -> str:
    from .html import fmt
    return fmt(float(x)) if fm == "sig" else f"{x:{fm}}"


def _pairs(a: dict, b: dict, specs) -> list[str]:
    """Rows of two columns: ``specs`` = (label, key, scale, format; "sig": 4 significant digits)."""
    return [_row(label, _cell(a[k] * sc, fm), _cell(b[k] * sc, fm)) for label, k, sc, fm in specs]


def _model_rows(v: float):
    """Rows of the junction table at the technology's reference bias ``v`` (names: ``report.names``)."""
    from .names import c_jdep, c_node, cg_jdep, fw_jdep, fw_jdep_cv, label
    return (("PD area (um2)", "area_m2", 1e12, ".2f"), ("PD perimeter (um)", "perimeter_m", 1e6, ".2f"),
            ("photoactive area (um2)", "photoactive_area_m2", 1e12, ".3f"),
            (label(c_jdep(v)), "c_jdep_F", 1e15, "sig"), (label(c_node(v)), "c_node_F", 1e15, "sig"),
            (label(cg_jdep(v)), "cg_V_per_e", 1e6, "sig"),
            (label(fw_jdep(v)), "fwc_e", 1e-3, ".1f"),
            (label(fw_jdep_cv(v)), "fwc_cv_e", 1e-3, ".1f"),
            ("dark current (fA)", "dark_current_A", 1e15, ".3f"))


_SIZE_ROWS = (("C_M", "c_m", 1.0, ".1f"), ("mask opening (um2)", "mask_open_m2", 1e12, ".3f"),
              ("t_int primary (us)", "t_int_primary_s", 1e6, ".1f"),
              ("t_int secondary (us)", "t_int_secondary_s", 1e6, ".1f"),
              ("trace at speed_min (px)", "trace_px_at_speed_min", 1.0, ".1f"),
              ("primary motion (px)", "motion_px_primary", 1.0, ".2f"))


def _response_rows(v: float):
    """Rows at the design's PD reset level ``v``: PD-referred and output-referred (column) gains."""
    from .names import c_jdep, c_node, cg_jdep, label
    return ((label(c_jdep(v)), "c_pd_F", 1e15, "sig"), (label(c_node(v)), "c_pd_node_F", 1e15, "sig"),
            ("C_FD (fF)", "c_fd_F", 1e15, "sig"), (label(cg_jdep(v)), "cg_pd_V_per_e", 1e6, "sig"),
            ("charge sharing C_node/(C_node+C_FD)", "sharing", 1.0, ".3f"),
            ("SF gain A_sf", "a_sf", 1.0, ".3f"),
            (label("CG_out(0)"), "cg_out_V_per_e", 1e6, "sig"))


def model_text(t: dict) -> str:
    lines = [f"Analytic models: {t['design']} ({t['technology']}, C_jdep at V_R = {t['reset_bias_V']:g} V)",
             _row("", "primary", "secondary"), *_pairs(t["primary"], t["secondary"], _model_rows(t["reset_bias_V"])),
             f"  C_A = A1/A2 = {t['c_a']:.3f}   C_C = C_jdep1/C_jdep2 = {t['c_c']:.3f}   "
             f"photoactive ratio = {t['photoactive_ratio']:.1f}"]
    if "at_reset" in t["primary"]:
        p, s = t["primary"]["at_reset"], t["secondary"]["at_reset"]
        lines += [f"At the design's reset bias ({p['v_bias_V']:g} V): PD-referred and output-referred (column) CG",
                  *_pairs(p, s, _response_rows(p["v_bias_V"]))]
    return "\n".join(lines)


def simulate_text(r: dict, reference: bool = False) -> str:
    """``reference``: the design is the test chip of [Thesis2019] (``experiments.reference``), whose
    printed currents the ratio is then set beside; for any other design they would mean nothing."""
    p, s, m = r["primary"], r["secondary"], r["model_vs_spice"]
    thesis = "thesis 1400 / 52 = 26.9; " if reference else ""
    lines = [f"Simulation experiment (fig. A.1 - A.3): exposure window {r['t_window_s'] * 1e6:g} us, "
             f"backend {r['backend']}, ngspice {r['ngspice_version']}",
             _row("", "primary", "secondary"),
             _row("output swing at the column (mV)", f"{p['swing_V'] * 1e3:.0f}", f"{s['swing_V'] * 1e3:.0f}"),
             _row("target (fraction of swing)", f"{p['target_frac']:.2f}", f"{s['target_frac']:.2f}"),
             _row("photocurrent at target (pA)", f"{p['i_mid_A'] * 1e12:.1f}", f"{s['i_5pct_A'] * 1e12:.1f}"),
             f"  i_mid / i_5pct = {r['ratio']:.1f} ({thesis}linear ideal (mid / low fraction) x C_C = "
             f"{r['ratio_ideal']:.1f})",
             f"  fig. A.1 (currents in ratio C_C): worst difference {r['fig_a1']['max_diff_frac'] * 100:.2f} % of swing",
             f"  analytic model vs SPICE over 10-90 % of swing: worst {m['max_err_frac'] * 100:.2f} %",
             f"  {r['n_runs']} SPICE runs ({r['n_cached']} from cache) in {r['wall_s']:.1f} s"]
    return "\n".join(lines + _retried_lines(r) + _failed_lines(r))


def _failed_lines(r: dict) -> list[str]:
    """Sweep points that did not simulate (the figures come from the others)."""
    return [f"  FAILED point ({x['sweep']} sweep, I_primary = {x['iph_primary_A'] * 1e9:.4g} nA, I_secondary = "
            f"{x['iph_secondary_A'] * 1e12:.4g} pA), left out: {x['message'][:300]}"
            + (f"; its deck and ngspice log are kept in {x['folder']}" if x.get("folder") else "")
            for x in r.get("failed_points", [])]


def _retried_lines(r: dict) -> list[str]:
    """Runs the engine re-ran with looser tolerances (their figures are less precise)."""
    return [f"  retried with looser tolerances: {x['deck']} ({x['reason'][:120]})" for x in r.get("retried", [])]


def size_text(r: dict) -> str:
    a, s, v = r["levels"]["analytic"], r["levels"]["spice"], r["verify"]
    lines = [f"Sizing ({r['level']} level chosen); sized design: {r['sized_design']}",
             _row("", "analytic", "SPICE level"), *_pairs(a, s, _SIZE_ROWS),
             f"  verify in SPICE: primary at {v['primary_frac'] * 100:.1f} % of swing, "
             f"secondary at {v['secondary_frac'] * 100:.1f} %",
             f"  analytic solve {r['solve_time_s'] * 1e3:.1f} ms",
             f"  why the levels differ: {r['why_levels_differ']}"]
    for row in r.get("sensitivity", []):
        lines.append(f"  {row['variant']:<22} C_M {row['c_m']:6.1f} ({row['c_m_change_frac'] * 100:+5.1f} %)  "
                     f"t_p {row['t_int_primary_s'] * 1e6:7.1f} us ({row['t_primary_change_frac'] * 100:+5.1f} %)")
    return "\n".join(lines + _retried_lines(r))


def report_text(r: dict) -> str:
    """Where the report is, its headline figures, which sections wait, and the diff's verdict."""
    c = r["checked"]
    where = r["html"] or r["out"]
    from .verdict import PROFILES, line
    lines = [f"report: {where}"]
    if r.get("verdict"):
        lines.append(f"  {line(r['verdict'])}")
    lines += [f"  {r['design']} rev {r['revision']} ({r['profile']} profile: {PROFILES.get(r['profile'], '')}): "
             f"{r['spice_runs']} SPICE runs, "
             f"{r['spice_cached']} from cache, {r['sections_from_cache']} sections from cache, {r['wall_s']} s"]
    from .html import fmt, unit
    for name, label in (("summary.primary.cg_jdep_uV_per_e", "primary CG_jdep(2.5 V)"),
                        ("summary.secondary.cg_jdep_uV_per_e", "secondary CG_jdep(2.5 V)"),
                        ("model_vs_spice.primary.i_mid_A", "primary i_mid"),
                        ("model_vs_spice.secondary.i_5pct_A", "secondary i_5pct"),
                        ("model_vs_spice.model_vs_spice.max_err_pct", "model vs SPICE worst"),
                        ("sizing.c_m", "C_M (sized)"), ("afe.gain_error_pct", "AFE gain error")):
        if name in c:
            lines.append(f"  {label:<24} {fmt(c[name]['value'])} {unit(c[name]['unit'])}".rstrip())
    for key, n in r.get("needs", {}).items():
        lines.append(f"  {key}: give {n['input']} ({n['why']})")
    failed = [k for k, v in r["sections"].items() if v in ("failed", "not yet available")]
    if failed:
        lines.append("  " + ", ".join(f"{k}: {r['sections'][k]}" for k in failed))
    for key, flags in r.get("flags", {}).items():   # the first sentence; the report gives the reason
        lines += [f"  flag ({key}): {x.split('. ')[0].rstrip('.')}." for x in flags]
    d = r.get("diff")
    if d:
        lines += diff_lines(d, unit)
    return "\n".join(lines)


def diff_lines(d: dict, unit) -> list[str]:
    """The revision diff's verdict: on specs (ranked by the margin each used) when the design has
    them, else on the checked figures."""
    if d.get("by_specs"):
        head = (f"diff against {d['baseline']}: " + (f"{len(d['newly_failing'])} spec(s) newly failing: "
                + ", ".join(d["newly_failing"]) if d["newly_failing"] else "no spec newly failing"))
    else:
        head = f"diff against {d['baseline']}: " + ("no checked figure moved beyond tolerance" if d["passed"]
                                                   else f"{len(d['moved'])} checked figure(s) moved beyond tolerance")
    lines = [head]
    lines += [f"  design: {x['field']}: {x['old']} -> {x['new']}" for x in d["design_changes"]]
    for x in d.get("specs", []):
        used = x.get("margin_used_pct")
        if x["verdict"] in ("pass", "not measured", "not run") and not used:
            continue
        lines.append(f"  {x['verdict'].upper():14s} {x['spec']}: {_num(x['old_value'])} -> {_num(x['new_value'])} "
                     f"{x['unit']} ({x['limit']}; margin {_num(x['old_margin_pct'])} -> {_num(x['new_margin_pct'])} %"
                     + (f", used {used:+.3g} points" if used is not None else "") + ")")
    word = "moved" if d.get("by_specs") else "FAIL"
    moved = [x for x in d["checked"] if x["status"] in ("moved", "removed")]
    moved.sort(key=lambda x: -(abs(x.get("delta", 0.0)) / x["tolerance"] if x.get("tolerance") else math.inf))
    for x in moved:
        new = "removed" if x["new"] is None else f"{x['new']:.4g}"
        lines.append(f"  {word} {x['figure']}: {x['old']:.4g} -> {new} {unit(x['unit'])} "
                     f"(tolerance {x.get('tolerance', 0):.3g})".rstrip())
    lines += [f"  netlist changed: {n['netlist']}" for n in d["netlists"]]
    return lines


def _num(x) -> str:
    return "-" if x is None else f"{x:.4g}"
