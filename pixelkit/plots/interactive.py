"""Interactive waveforms (plotly): zoom, pan, hover read-out, traces chosen from the legend.

Output works with no network: plotly.js is inlined once per page (``plotly_js``), each figure
is a ``<div>`` and its data (``figure_div``). Times in us, levels in V, as the simulator gives
them; the measurement's readings are markers on their trace, labelled with what was read.
"""
from __future__ import annotations

import html

#: plotly's mode bar without its logo; responsive to the page's width
CONFIG = {"displaylogo": False, "responsive": True, "scrollZoom": True}
_DASH = {"nominal": "dot", "worst": "solid"}


def plotly_js() -> str:
    """plotly.js itself, for one ``<script>`` of the page."""
    from plotly.offline import get_plotlyjs
    return get_plotlyjs()


def figure(traces: list[dict], marks: list[dict], title: str, y_title: str = "V"):
    """A plotly figure: ``traces`` [{name, t (s), v, role?}], ``marks`` [{t, v, what, role?, condition?}]."""
    import plotly.graph_objects as go
    fig = go.Figure()
    for tr in traces:
        fig.add_trace(go.Scatter(x=[t * 1e6 for t in tr["t"]], y=tr["v"], mode="lines", name=tr["name"],
                                 legendgroup=tr.get("role"), line={"width": 1.2, "dash": _DASH.get(tr.get("role"),
                                                                                                   "solid")}))
    for role in dict.fromkeys(m.get("role") for m in marks):
        ms = [m for m in marks if m.get("role") == role]
        fig.add_trace(go.Scatter(
            x=[m["t"] * 1e6 for m in ms], y=[m["v"] for m in ms], mode="markers",
            name="readings" + (f" @ {role}" if role else ""), legendgroup=role,
            marker={"symbol": "x" if role == "nominal" else "circle-open", "size": 10, "line": {"width": 2}},
            text=[f"{m['what']}: {m['v']:.6g} V at {m['t'] * 1e6:.6g} us" + (f" ({m['condition']})" if
                                                                              m.get("condition") else "")
                  for m in ms], hoverinfo="text"))
    fig.update_layout(title={"text": title, "font": {"size": 14}}, xaxis_title="time (us)", yaxis_title=y_title,
                      height=420, margin={"l": 60, "r": 20, "t": 50, "b": 50}, template="plotly_white",
                      legend={"font": {"size": 10}}, hovermode="closest")
    return fig


def figure_div(fig, div_id: str) -> str:
    """The figure as a ``<div>`` and its script, plotly.js not included (``plotly_js`` once per page)."""
    return fig.to_html(full_html=False, include_plotlyjs=False, div_id=div_id, config=CONFIG)


def page(title: str, body: list[str]) -> str:
    """A standalone page: plotly.js inlined once, then ``body`` (HTML fragments, figures' divs)."""
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(title)}</title><script>{plotly_js()}</script>"
            "<style>body{font:14px/1.5 'DejaVu Sans',Arial,sans-serif;margin:16px 24px;color:#1d2330}"
            "p.meta{color:#5b6474;font-size:13px}</style></head><body>\n" + "\n".join(body) + "\n</body></html>\n")


def raw_page(path, plots: list[dict], vectors: list[str] | None = None) -> str:
    """The page of ``pixelkit waves``: every plot of a raw file (``spice.raw.read_raw``), each vector
    against the plot's first (time, frequency, or the swept source), one figure per plot."""
    body = [f"<h1>{html.escape(str(path.name))}</h1>"]
    for k, p in enumerate(plots):
        names = p["names"]
        x_name, ys = names[0], [n for n in names[1:] if vectors is None or n in vectors]
        x = p["data"][x_name].real
        traces = [{"name": n, "t": (x if x_name == "time" else x * 1e-6).tolist(), "v": p["data"][n].real.tolist()}
                  for n in ys]
        fig = figure(traces, [], f"{p['plotname']} ({len(x)} points)", "V or A")
        if x_name != "time":
            fig.update_layout(xaxis_title=x_name)
        body.append(f"<p class=\"meta\">plot {k + 1} of {len(plots)}: {html.escape(p['plotname'])}; "
                    f"vectors {html.escape(', '.join(ys))}</p>")
        body.append(figure_div(fig, f"plot{k}"))
    return page(f"{path.name}: waveforms", body)
