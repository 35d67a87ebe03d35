"""``pixelkit signoff``: the sign-off of a layout the kit did not draw (or drew and the designer edited).

From a GDSII / OASIS file, the designer's SPICE netlist of its top cell and the technology:

1. the inputs checked (``signoff.gds_in``, ``signoff.netlist_in``): a bad file, cell, layer, label or
   device is refused (exit 2) before any deck runs;
2. the foundry's DRC deck and its LVS deck (fd_pv, deep mode) started side by side in private folders
   (``signoff.drc``, ``signoff.foundry``), with ``--chip`` the density and antenna decks too;
3. meanwhile the kit's LVS (``signoff.lvs.compare_view``: every mismatch named by net, device and
   parameter), the extraction of the cell (``pex.nets.view_geometry``: every net paired with the
   netlist's through the LVS cross reference, whose names the layout's labels must agree with;
   ``pex.capacitance``), the post-layout netlist (the designer's cards flattened, with the wiring
   capacitances) and the light map (every junction no metal covers, by net);
4. with ``--with-design``, the design's own products from the same file: the post-layout view every SPICE
   command takes with ``--post-layout`` when the design names the file in ``[layout] gds``
   (``pex.overlay``), and the light map's output error through the readout by SPICE.

Outputs go to ``--out``, each file written to a temporary in that folder and renamed into place (a link
placed there is replaced, never written through). The verdict is ``flow.verdict``'s: 1 when a check
that ran failed, 5 when one asked could not run (a deck not installed, extraction without a stack),
else 0.
"""
from __future__ import annotations

import json
import tempfile
import time
from pathlib import Path

from ..errors import PixelkitError
from ..fileio import json_default, out_folder, write_atomic

CHECKS = ("drc", "lvs", "foundry-lvs", "pex", "lightmap")
CHIP_CHECKS = ("density", "antenna")


def signoff(gds, netlist, tech, out: Path, top: str | None = None, skip: tuple = (), chip: bool = False,
            design=None) -> dict:
    """Sign off cell ``top`` of ``gds`` against ``netlist`` (paths); the result dict (``verdict`` reads it)."""
    from .flow import verdict
    from .signoff.gds_in import read_layout
    from .signoff.netlist_in import read_netlist
    from .signoff.schematic import spice_text
    t_start = time.perf_counter()
    out = Path(out)
    asked = [c for c in CHECKS if c not in skip] + ([c for c in CHIP_CHECKS if c not in skip] if chip else [])
    with tempfile.TemporaryDirectory(prefix="pixelkit-signoff-") as tmp:
        tmp = Path(tmp)
        lay = read_layout(gds, tech, top, tmp)                       # exit 2 here, before any deck
        top = lay.top
        nl = read_netlist(netlist, tech)
        if nl.circuit_name(top) is None:
            raise PixelkitError(f"{netlist}: no .subckt {top} (the top cell of {gds}); its subcircuits: "
                                + ", ".join(nl.circuits))
        view = nl.top_view(top)
        _check_devices(lay, view, tech, nl)
        out_folder(out, root=True)   # a device, a file or a dangling link there: refused (fileio)
        result = {"gds": str(gds), "netlist": str(netlist), "top": top, "technology": tech.name, "checks": asked,
                  "cells": lay.cells}
        jobs = _start_decks(lay.path, top, tech, out, asked, spice_text(view, f"{Path(netlist).name}, {top}"))
        try:
            kit_lvs = None
            if "lvs" in asked or "pex" in asked:     # the kit's LVS in a forked child beside the extraction
                from .pex.beside import MIN_POLYGONS, beside
                from .signoff.lvs import compare_view
                kit_lvs = beside(compare_view, MIN_POLYGONS, lay.path, top, tech, view, tmp)   # any cell: forked
            extracted = None
            if "pex" in asked or "lightmap" in asked:
                try:
                    extracted = _extraction_or_error(lay.path, top, tech, view, nl, tmp, asked)
                except BaseException:
                    if kit_lvs is not None:
                        kit_lvs.cancel()
                    raise
            if kit_lvs is not None:
                lvs = kit_lvs()
                result["lvs"] = lvs.as_dict()
                if lvs.report:
                    result["lvs"]["report"] = str(write_atomic(out / f"{top}.lvsdb", Path(lvs.report).read_bytes()))
            if extracted is not None:
                if result.get("lvs") is not None and not result["lvs"]["match"]:
                    extracted = _extraction(lay.path, top, tech, view, nl, out, result["lvs"], asked)   # why not run
                elif isinstance(extracted, Exception):
                    raise extracted
                else:
                    extracted = _moved_out(extracted, tmp, out)
                result.update(extracted)
            if design is not None:
                result["design"] = _design_products(lay.path, top, design, out, asked)
        finally:
            for key, job in jobs.items():
                result[key] = _finished(job)
        if "lvs" not in asked:
            result.pop("lvs", None)
    result["seconds"] = round(time.perf_counter() - t_start, 2)
    result["exit_status"] = verdict(result)
    write_atomic(out / "signoff.json", json.dumps(result, indent=1, default=json_default))
    return result


def _start_decks(gds: Path, top: str, tech, out: Path, asked: list, spice: str) -> dict:
    """The decks, started now in private folders: {result key: Job or NotRun}."""
    from .signoff.foundry import Job, start_chip_drc, start_lvs
    jobs = {}
    if "drc" in asked:
        from .signoff.drc import drc_command, drc_result

        def args(tmp):
            a, report, log, deck, options = drc_command(gds, top, tech, tmp)
            args.meta = (report, log, deck, options)
            return a[2:]          # Job adds the binary and -b

        def finish(code, _log, tmp):
            report, log, deck, options = args.meta
            (tmp / "run.log").replace(log)
            r = drc_result(code, gds, top, report, log, deck, options, jobs["drc"].seconds())
            d = r.as_dict()
            d["report"] = str(write_atomic(out / f"{top}.lyrdb", report.read_bytes()))
            write_atomic(out / f"{top}.drc.log", log.read_bytes())
            return d
        jobs["drc"] = Job(args, finish, "pixelkit-drc-")
    if "foundry-lvs" in asked:
        jobs["foundry_lvs"] = start_lvs(gds, top, spice, tech, out)
    for which in CHIP_CHECKS:
        if which in asked:
            jobs[which] = start_chip_drc(gds, top, tech, out, which)
    return jobs


def _finished(job) -> dict:
    from .signoff.foundry import NotRun
    if isinstance(job, NotRun):
        return job.as_dict()
    r = job.result()
    d = r if isinstance(r, dict) else r.as_dict()
    return {"run": True, **d}


def _check_devices(lay, view, tech, nl) -> None:
    """A device kind the netlist names that the layout has none of the layers to form: refused (exit 2)."""
    import klayout.db as kdb
    cell = lay.layout.cell(lay.top)

    def has(name):
        if name not in tech.layout.layers and name not in tech.layout.aliases:
            return False
        layer = tech.layer(name)
        li = lay.layout.find_layer(layer.layer, layer.datatype)
        return li is not None and not kdb.Region(cell.begin_shapes_rec(li)).is_empty()
    need = {}
    for c in view:
        for name, model, *_ in c["mos"]:
            need.setdefault(("active", "poly"), (c["name"], name, model))
            if model == tech.mos.pmos:
                need.setdefault(("nwell", "pplus"), (c["name"], name, model))
        for name, _a, _k, model, *_ in c["diodes"]:
            need.setdefault(("nwell", "pd_marker"), (c["name"], name, model))
        for name, _a, _b, model, *_ in c["caps"]:
            need.setdefault(("mim_top", "mim_marker"), (c["name"], name, model))
        for name, _a, _b, model, *_ in c["res"]:
            need.setdefault(("sab", "res_marker"), (c["name"], name, model))
    for layers, (circuit, name, model) in need.items():
        missing = [x for x in layers if not has(x)]
        if missing:
            from ..errors import ConfigError
            card = next(c for c in nl.circuits[circuit]["cards"] if c.name[1:] == name)
            raise ConfigError(f"{nl.path}:{card.line}", f"device {card.name} of {circuit}", model,
                              f"a device the layout can have: cell {lay.top} of {lay.source} has no "
                              f"{' / '.join(missing)} shape, so it contains no {model}")


def _extraction(gds: Path, top: str, tech, view, nl, out: Path, lvs: dict | None, asked: list) -> dict:
    """The cell's wiring capacitances, its post-layout netlist and its light map (exposed junctions)."""
    from .pex.capacitance import capacitances
    from .pex.light import KINDS, exposed
    from .pex.nets import view_geometry
    from .signoff.netlist_in import post_layout_text
    res = {}
    why = None
    if tech.stack is None:
        why = f"technology {tech.name} has no [stack] (conductor heights, thicknesses, dielectrics)"
    elif lvs is not None and not lvs["match"]:
        why = "the layout does not match its netlist (LVS above), so its nets cannot be named"
    if why is not None:
        for k in ("pex", "lightmap"):
            if k in asked:
                res[k] = {"run": False, "check": k, "reason": why}
        return res
    t0 = time.perf_counter()
    geo = view_geometry(gds, top, tech, view)
    if "pex" in asked:
        cpl = capacitances(geo, tech.stack)
        pairs = {k: v for k, v in cpl.items() if v > 1e-19}
        rows = ["net_a,net_b,C_F"] + [f"{a},{b},{c:.6e}" for (a, b), c in sorted(pairs.items())]
        nets = sorted({n for k in pairs for n in k})
        totals = {n: cpl.total(n) for n in nets}
        res["pex"] = {"run": True, "nets": len(nets), "couplings": len(pairs), "stack": tech.stack.source,
                      "total_F": totals, "seconds": round(time.perf_counter() - t0, 2),
                      "table": str(write_atomic(out / f"{top}.caps.csv", "\n".join(rows) + "\n")),
                      "post_layout_netlist": str(write_atomic(out / f"{top}.post.spice", post_layout_text(
                          nl, top, pairs, f"post-layout netlist of {top} ({Path(str(gds)).name})")))}
    if "lightmap" in asked:
        js = exposed(geo, "pixels")
        rows = ["net,kind,area_m2"] + [f"{j.net},{KINDS[j.kind]},{j.area_m2:.6e}" for j in js]
        res["lightmap"] = {"run": True, "open_m2": sum(j.area_m2 for j in js),
                           "junctions": [{"net": j.net, "kind": KINDS[j.kind], "area_m2": j.area_m2} for j in js],
                           "table": str(write_atomic(out / f"{top}.lightmap.csv", "\n".join(rows) + "\n"))}
    return res


def _extraction_or_error(gds: Path, top: str, tech, view, nl, tmp: Path, asked: list):
    """``_extraction`` into the private folder ``tmp`` (the kit's LVS, beside it, decides whether its
    files are kept), or the PixelkitError it raised (a layout its netlist does not match)."""
    try:
        return _extraction(gds, top, tech, view, nl, tmp, None, asked)
    except PixelkitError as e:
        return e


def _moved_out(res: dict, tmp: Path, out: Path) -> dict:
    """``res`` with the files it wrote into ``tmp`` renamed into ``out`` (write_atomic: no link followed)."""
    for part in res.values():
        for key in ("table", "post_layout_netlist"):
            if isinstance(part, dict) and part.get(key):
                src = Path(part[key])
                part[key] = str(write_atomic(out / src.name, src.read_bytes()))
    return res


def _design_products(gds: Path, top: str, design, out: Path, asked: list) -> dict:
    """The design's post-layout view and light map from the cells of ``gds`` (the kit's cell names)."""
    from .pex.overlay import from_gds
    res = {}
    if "pex" in asked:
        p = from_gds(design, gds)
        res["post_layout"] = {"source": p.source, "column_cap_F": p.column_cap,
                              "fd_F": {k: v for k, v in p.per_row.items() if k.endswith(".fd")},
                              "file": str(write_atomic(out / "post_layout.json", json.dumps(
                                  p.as_dict(), indent=1, default=json_default)))}
    if "lightmap" in asked:
        from .pex import gds_geometry
        from .pex.light import light_map
        geos = gds_geometry(design, gds, ("DUALPIX_COL", "AFE_P", "AFE_S"), context=top)
        lm = light_map(design, "pixels", geos=geos)
        res["lightmap"] = {k: lm[k] for k in ("irradiance_W_m2", "columns", "readout_area_m2", "afe_area_m2",
                                              "worst_error_over_noise")}
    return res
