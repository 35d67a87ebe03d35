"""``pixelkit waves FILE.raw``: any ngspice raw file the kit wrote, as interactive waveforms (HTML)."""
from __future__ import annotations

from pathlib import Path

import click

from .types import FilePath

from .common import emit, json_opt, main


@main.command("waves")
@click.argument("raw", type=FilePath(dir_okay=False))
@click.option("--out", type=FilePath(dir_okay=False), default=None,
              help="the HTML file to write (default: FILE.html beside the raw file)")
@click.option("--vectors", default=None, metavar="V,V,...",
              help="only these vectors, as the raw file names them (v(col_p),i(vdd)); default: all")
@json_opt
def waves_cmd(raw, out, vectors, as_json):
    """Write an ngspice raw file (the report's waveforms, `--waveforms F.raw`, `ngspice -r`) as one HTML
    page of interactive waveforms: zoom, pan, hover read-out, traces chosen from the legend; plotly.js
    inlined, so the page works with no network."""
    from ..errors import ConfigError
    from ..fileio import check_output, write_atomic
    from ..plots.interactive import raw_page
    from ..readfile import read_bytes
    from ..spice.raw import parse_raw
    path = Path(raw)
    if path.suffix.lower() != ".raw":
        raise ConfigError("", "RAW", str(path), "an ngspice raw file whose name ends in .raw")
    plots = parse_raw(read_bytes(path, "RAW", "raw"), path)
    names = {n for p in plots for n in p["names"][1:]}
    chosen = None
    if vectors is not None:
        chosen = [v.strip().lower() for v in vectors.split(",") if v.strip()]
        unknown = [v for v in chosen if v not in names]
        if unknown or not chosen:
            raise ConfigError("", "--vectors", vectors, f"vectors of the file: {', '.join(sorted(names)[:30])}")
    target = check_output(Path(out) if out else path.with_suffix(".html"))
    if target.suffix.lower() not in (".html", ".htm"):
        raise ConfigError("", "--out", str(target), "a file name ending in .html")
    write_atomic(target, raw_page(path, plots, chosen))
    emit({"html": str(target), "plots": len(plots), "vectors": sorted(chosen or names)}, as_json,
         lambda r: f"waves: {r['html']} ({r['plots']} plot(s), {len(r['vectors'])} vector(s))")
