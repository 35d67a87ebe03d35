"""Render the report's HTML (jinja2): one page, styles inline, pictures as files beside it."""
from __future__ import annotations

import math
from pathlib import Path

import jinja2

_ENV = jinja2.Environment(loader=jinja2.PackageLoader("pixelkit", "report/templates"),
                          autoescape=jinja2.select_autoescape(["html", "j2"]), trim_blocks=True, lstrip_blocks=True)


def fmt(x) -> str:
    """Numbers to 4 significant digits, trailing zeros kept (3.9996 is 4.000, never a bare 4 beside
    11.24); integers as they are; anything else as text."""
    if isinstance(x, bool) or x is None:
        return "" if x is None else str(x)
    if isinstance(x, int):
        return str(x)
    if isinstance(x, float):
        if not math.isfinite(x):
            return str(x)
        s = f"{x:#.4g}"
        return s[:-1] if s.endswith(".") else s
    return str(x)


def tol(x) -> str:
    """A tolerance as stated (3 significant digits, no trailing zeros): 0.5 %, 0.002 V."""
    return f"{x:.3g}"


def unit(u: str) -> str:
    """A unit as printed: dimensionless figures (unit "1" in summary.json) carry none."""
    return "" if u in ("1", None) else u


def _template_for(key: str) -> str:
    name = f"sections/{key}.html.j2"
    try:
        _ENV.get_template(name)
        return name
    except jinja2.TemplateNotFound:
        return "sections/_generic.html.j2"


def render(folder: Path, design, sections, summary: dict, diff: dict | None) -> Path:
    css = (Path(__file__).parent / "templates" / "report.css").read_text()
    blocks = [(s, _template_for(s.key)) for s in sections]
    so = next((s for s in sections if s.key == "signoff" and s.available), None)
    waves = set((so.data.get("waves") or {}) if so else ())
    plotly = ""
    if waves:   # plotly.js once per page, every waveform a <div> and its data
        from ..plots.interactive import plotly_js
        plotly = plotly_js()
    html = _ENV.get_template("report.html.j2").render(design=design, blocks=blocks, summary=summary, diff=diff,
                                                      css=css, f=fmt, u=unit, tol=tol, waves=waves, plotly=plotly,
                                                      wave_div=wave_div)
    path = Path(folder) / "index.html"
    path.write_text(html)
    return path


def wave_div(w: dict) -> str:
    """A spec's waveform view (``verify.waves.spec_waves``) as an interactive figure's ``<div>``."""
    from ..plots.interactive import figure, figure_div
    what = w["spec"] if w["figure"] == w["spec"] else f"{w['spec']} ({w['figure']})"
    title = f"{what}: {w['worst']}" + ("" if w["worst"] == w["nominal"] else f" vs {w['nominal']}")
    return figure_div(figure(w["traces"], w["marks"], title), f"plot-{w['spec']}")
