"""The text of a sign-off result (``pixelkit signoff``, and ``pixelkit layout`` of a 4T design and its
foundry checks): one module both commands import."""
from __future__ import annotations

from pathlib import Path


def foundry_lines(x: dict) -> list:
    """The foundry LVS / density / antenna results of a sign-off result, as text lines."""
    lines = []
    for key, what in (("foundry_lvs", "foundry LVS"), ("density", "density"), ("antenna", "antenna")):
        v = x.get(key)
        if v is None:
            continue
        if not v.get("run", True):
            lines.append(f"{what}: NOT RUN - {v['reason']}")
        elif key == "foundry_lvs":
            lines.append(f"{what} (fd_pv deck, deep, {v['top']}, {v['seconds']:g} s): "
                         + ("Netlists match" if v["match"] else "Netlists don't match"))
            lines += [f"  {m}" for m in v["mismatches"]]
        else:
            lines.append(f"{what} (fd_pv deck, {v['top']}, {v['seconds']:g} s): "
                         + ("clean" if v["clean"] else f"{v['total']} violation(s)"))
            lines += [f"  {r['rule']} x{r['count']} in {r['cell']}: {r['description'].splitlines()[0]}"
                      for r in v["violations"]]
    return lines


def _drc(d: dict) -> list:
    return [f"DRC ({Path(d['deck']).name}, {d['klayout']}, {d['seconds']:g} s): "
            + ("clean" if d["clean"] else f"{d['total']} violation(s)")] + \
        [f"  {v['rule']} x{v['count']} in {v['cell']}: {v['description'].splitlines()[0]} (first at {v['where']})"
         for v in d["violations"]]


def _pex(p: dict) -> list:
    big = sorted(p["total_F"].items(), key=lambda kv: -kv[1])[:8]
    return [f"extraction ({p['seconds']:g} s): {p['nets']} nets, {p['couplings']} couplings -> {p['table']}; "
            f"post-layout netlist {p['post_layout_netlist']}",
            "  largest totals: " + ", ".join(f"{n} {c * 1e15:.3f} fF" for n, c in big)]


def _light(lm: dict) -> list:
    return [f"light map: {lm['open_m2'] * 1e12:.4g} um2 of junction no metal covers -> {lm['table']}"] + \
        [f"  {j['net']}: {j['kind']} {j['area_m2'] * 1e12:.4g} um2" for j in lm["junctions"][:8]]


def signoff_text(r: dict) -> str:
    lines = [f"{r['gds']}: cell {r['top']} against {r['netlist']} ({r['technology']}, {r['seconds']:g} s)"]
    for key, what, render in (("drc", "DRC", _drc), ("lvs", "LVS", None), ("pex", "extraction", _pex),
                              ("lightmap", "light map", _light)):
        x = r.get(key)
        if x is None:
            continue
        if not x.get("run", True):
            lines.append(f"{what}: NOT RUN - {x['reason']}")
        elif render is not None:
            lines += render(x)
        else:
            lines.append(f"LVS (kit extraction, {x['seconds']:g} s): " + (f"match ({x['nets']} nets in {r['top']})"
                         if x["match"] else f"{len(x['mismatches'])} mismatch(es)"))
            lines += [f"  {m}" for m in x["mismatches"]]
            lines += foundry_lines(r)
    dz = r.get("design")
    if dz:
        if "post_layout" in dz:
            pl = dz["post_layout"]
            lines.append(f"post-layout view of the design -> {pl['file']} (every SPICE command uses it with "
                         "--post-layout when the design names this GDS in [layout] gds): FD "
                         + ", ".join(f"{k} {v * 1e15:.3f} fF" for k, v in pl["fd_F"].items()))
        if "lightmap" in dz:
            lines += [f"light map through the readout: {c} AFE output error {x['error_V'] * 1e3:+.3f} mV "
                      f"({x['error_over_noise']:.1f} x the read noise)" for c, x in dz["lightmap"]["columns"].items()]
    lines.append({0: "signed off: every check asked ran and passed", 1: "NOT signed off: a check failed",
                  5: "NOT signed off: a check asked did not run"}[r["exit_status"]])
    return "\n".join(lines)
