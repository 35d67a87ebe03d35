"""``pixelkit report``: build every section, write the HTML, its data and summary.json.

The report is built in a temporary folder beside ``out`` and renamed into place
when complete, so a failed or interrupted run never leaves a half-written report
(the previous one stays until the new one is whole).
"""
from __future__ import annotations

import csv
import io
import json
import os
import shutil
import time
import traceback
from pathlib import Path

from .. import owner as owners
from ..errors import ConfigError, PixelkitError
from ..fileio import honour_umask_tree, json_default, out_folder, path_kind, staging_dir
from ..spice.counter import SpiceCounter
from . import cache, datasheet
from .diff import diff_reports, load_report
from .html import render
from .portable import portable_section
from .verdict import verdict
from .sections import REGISTRY, Context, Section, load_section

#: Sections whose output depends on the --measured file.
MEASURED_SECTIONS = ("gap",)
#: Sections that --exhaustive changes (the sign-off's Monte Carlo runs its full count).
EXHAUSTIVE_SECTIONS = ("signoff",)


def _planned(title: str, key: str, owner: str) -> Section:
    return Section.unavailable(title, f"not yet available: {owner} will add pixelkit/report/sections/{key}.py "
                                      "when that capability lands")


def _start_background(ctx: Context, options_of, use_cache: bool, registry=REGISTRY) -> dict:
    """Start the background work of every section that has some (a module-level ``prefetch(ctx)``:
    the sign-off's verify, most of the report's SPICE work) unless the section comes from the
    cache: {key: (section from the cache, "cache")} or {key: (None, "background")}. The sections
    are then built in the main thread one after the other (their pictures: matplotlib is not
    thread-safe), those with background work last, while it runs on the cores they leave idle."""
    out = {}
    for key, _title, _owner in registry:
        mod = load_section(key)
        if mod is None or not hasattr(mod, "prefetch"):
            continue
        s = cache.load(cache.section_key(key, ctx.design, options_of(key)), ctx.out_dir) if use_cache else None
        if s is not None:
            out[key] = (s, "cache")
        else:
            mod.prefetch(ctx)
            out[key] = (None, "background")
    return out


def _build_order(background: dict, registry=REGISTRY) -> list:
    """The registry with the sections whose work runs in the background moved to the end."""
    return ([r for r in registry if background.get(r[0], (0, ""))[1] != "background"]
            + [r for r in registry if background.get(r[0], (0, ""))[1] == "background"])


def build_section(key: str, title: str, owner: str, ctx: Context, options: dict, use_cache: bool) -> tuple:
    """(Section, 'cache' | 'built' | 'planned' | 'failed')."""
    mod = load_section(key)
    if mod is None:
        return _planned(title, key, owner), "planned"
    extra = getattr(mod, "inputs", None)   # files a section reads besides the design (closure: close.json)
    k = cache.section_key(key, ctx.design, {**options, **extra(ctx)} if extra else options)
    if use_cache:
        s = cache.load(k, ctx.out_dir)
        if s is not None:
            return s, "cache"
    try:
        s = mod.build(ctx)
    except Exception as exc:  # noqa: BLE001 - one failed section must not lose the others
        if os.environ.get("PIXELKIT_DEBUG"):
            traceback.print_exc()
        kind = "" if isinstance(exc, PixelkitError) else f"{type(exc).__name__}: "
        return Section(getattr(mod, "TITLE", title), available=False, failed=True, why=f"failed: {kind}{exc}"), "failed"
    s.key = key
    portable_section(s, ctx.out_dir)   # before the cache keeps it: no path of this run's staging folder
    if use_cache:
        cache.save(k, s, ctx.out_dir)
    return s, "built"


def _csv(table) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(table.columns)
    w.writerows(table.rows)
    return buf.getvalue()


def as_percent(c):
    """A checked fraction (unit "1", name ``*_frac``) as people read it everywhere else in the report:
    ``*_pct`` in %, its absolute tolerance scaled alike (one unit per figure: the tables and the
    terminal show %; ``diff.RENAMED_PCT`` compares a baseline's fraction with it)."""
    from dataclasses import replace
    if c.unit == "1" and c.name.endswith("_frac"):
        return replace(c, name=c.name[:-5] + "_pct", value=100.0 * c.value, unit="%", tol_abs=100.0 * c.tol_abs)
    return c


def _checked(sections) -> dict:
    out = {}
    for s in sections:
        for c in s.checked:
            if c.name in out:
                raise PixelkitError(f"report: checked figure {c.name!r} appears twice (sections "
                                    f"{out[c.name]['section']} and {s.key})")
            out[c.name] = {"value": float(c.value), "unit": c.unit, "tol_rel": c.tol_rel, "tol_abs": c.tol_abs,
                           "section": s.key, "note": c.note}
    return out


def _file_content(design) -> dict:
    """The design file's tables (a family design keeps no ``raw``: read again, as loaded)."""
    from ..schema import read_toml
    return read_toml(Path(design.source), "design") if getattr(design, "source", None) else {}


def _write_outputs(stage: Path, design, sections, meta: dict) -> dict:
    tables = {}
    for s in sections:
        for t in s.tables:
            if t.name in tables:
                raise PixelkitError(f"report: table name {t.name!r} used twice")
            (stage / f"{t.name}.csv").write_text(_csv(t))
            tables[t.name] = {"section": s.key, "caption": t.caption, "columns": t.columns, "rows": t.rows}
        if s.data:
            (stage / f"data_{s.key}.json").write_text(json.dumps(s.data, indent=1, default=json_default))
    raw = design.raw if hasattr(design, "raw") else _file_content(design)
    (stage / "design.json").write_text(json.dumps(raw, indent=1, default=json_default) + "\n")
    summary = {"design": design.name, "revision": design.revision, **meta,
               "sections": {s.key: s.status for s in sections},
               "needs": {s.key: {"input": s.needs, "why": s.why} for s in sections if s.needs},
               "flags": {s.key: list(s.flags) for s in sections if s.flags},
               "checked": _checked(sections)}
    signoff = next((s.data.get("rows") for s in sections if s.key == "signoff" and s.available), None)
    if signoff:   # the verdict of the sign-off section, for the terminal and the diff
        summary["signoff"] = {"specs": len(signoff), "failed": [r["spec"] for r in signoff if r["status"] == "fail"],
                              "not_measured": [r["spec"] for r in signoff if r["status"] == "not measured"]}
    (stage / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    (stage / "tables.json").write_text(json.dumps(tables, indent=1, default=json_default) + "\n")
    return summary


def _swap_into_place(stage: Path, out: Path) -> None:
    """Rename the finished stage to ``out`` (the earlier report, if any, moved aside and removed).
    Ctrl-C is held off between the two renames, so ``out`` is never left missing by it."""
    import signal
    old = None
    if path_kind(out) is not None:
        if path_kind(out / "summary.json") is None and any(out.iterdir()):
            raise ConfigError("", "--out", str(out), "a new folder or an earlier report folder (it has no summary.json)")
        old = out.with_name(f".{out.name}.old-{owners.tag()}")
    held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        if old is not None:
            os.replace(out, old)
        os.replace(stage, out)
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def _clear_debris(out: Path) -> None:
    """What killed runs left beside ``out``: an earlier report moved aside by a run killed between
    its two renames is put back; staging folders of runs that are gone are removed."""
    if path_kind(out) is None:
        for p in sorted(out.parent.glob(f".{out.name}.old-pk*")):
            if not owners.alive(owners.owner_of(p.name) or ""):
                os.replace(p, out)
                break
    owners.sweep(out.parent, f".{out.name}.")


def build_report(design, out: Path, *, quick: bool = False, backend: str = "batch", jobs: int | None = None,
                 measured: Path | None = None, baseline: Path | None = None, use_cache: bool = True,
                 html: bool = True, waves: tuple = (), exhaustive: bool = False, registry=None) -> dict:
    """Build the report of ``design`` into ``out``; returns the summary (with the diff when asked).
    ``registry``: the sections (default ``REGISTRY``; a pixel read by role: ``ROLE_REGISTRY``)."""
    registry = REGISTRY if registry is None else registry
    from ..progress import command_bar
    t0 = time.perf_counter()
    out = Path(out)
    base = load_report(Path(baseline)) if baseline else None
    if measured is not None and path_kind(measured) != "file":
        raise ConfigError("", "--measured", str(measured), "an existing CSV file of measured rows")
    if path_kind(out) not in (None, "dir"):
        raise ConfigError("", "--out", str(out), "a folder (a new one, or an earlier report's)")
    if os.path.islink(out):   # the report replaces the folder whole: a link would be replaced, not followed
        raise ConfigError("", "--out", str(out), "a folder, not a symbolic link (the report replaces the folder it "
                                                 "names as a whole; give the folder the link points to)")
    out_folder(out.parent)
    _clear_debris(out)
    stage = staging_dir(out.parent, f".{out.name}.new-{owners.tag()}-")
    try:
        sections, how = [], {}
        with command_bar("report", total=len(registry), unit="sections", eta=False) as bar:
            # counts SPICE runs (within ``with counter`` below, where ``ctx`` exists) and the sign-off's progress
            counter = SpiceCounter(lambda c: bar.set_postfix_str(
                "; ".join(x for x in (c.text(), ctx.progress_text()) if x), refresh=True))

            def tell(stage_name, done=None, total=None):
                bar.set_description(f"report: {stage_name}" + (f" {done}/{total}" if total else ""))

            ctx = Context(design, stage, quick, backend, jobs, Path(measured) if measured else None, tell,
                          waves=tuple(waves), exhaustive=exhaustive)
            measured_hash = cache.file_hash(measured) if measured else None

            def options_of(key):
                options = {"quick": quick, "backend": backend}
                if key in EXHAUSTIVE_SECTIONS and exhaustive:
                    options["exhaustive"] = True
                if key in MEASURED_SECTIONS:
                    options["measured"] = measured_hash
                if key == "signoff" and waves:
                    options["waves"] = sorted(waves)
                return options

            with counter:
                built = _start_background(ctx, options_of, use_cache, registry)
                for key, title, owner in _build_order(built, registry):
                    tell(title + (" (the sign-off beside it)" if ctx.background() else ""))
                    if key not in built or built[key][0] is None:
                        built[key] = build_section(key, title, owner, ctx, options_of(key), use_cache)
                    s, how[key] = built[key]
                    s.key = key
                    s.checked = [as_percent(c) for c in s.checked]
                    bar.update(1)
                sections = [built[key][0] for key, _t, _o in registry]
            bar.set_description("report")
        meta = {"profile": "quick" if quick else "full", "exhaustive": exhaustive, "backend": backend,
                "spice_runs": counter.runs, "spice_cached": counter.cached,
                "sections_from_cache": sum(v == "cache" for v in how.values()),
                "wall_s": None}
        summary = _write_outputs(stage, design, sections, meta)
        result = {"summary": summary, "how": how}
        if base is not None:
            result["diff"] = diff_reports(base, stage)
            (stage / "diff.json").write_text(json.dumps(result["diff"], indent=1) + "\n")
        signoff = next((s.data for s in sections if s.key == "signoff" and s.available), None)
        summary["verdict"] = verdict(summary, signoff, result.get("diff"))
        summary["wall_s"] = round(time.perf_counter() - t0, 2)
        (stage / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
        if html:
            render(stage, design, sections, summary, result.get("diff"))
            sheet = datasheet.render(stage, design, sections, summary)
            pdf, why = datasheet.print_pdf(sheet)
            summary["datasheet"] = {"html": sheet.name, "pdf": pdf.name if pdf else None, "why": why}
            (stage / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
        honour_umask_tree(stage)   # cached section files keep the cache's modes otherwise
        _swap_into_place(stage, out)
    except BaseException:
        if "ctx" in locals() and ctx.background():   # an interrupt: its ngspice runs end too
            from ..spice.batch import abort_runs
            abort_runs()
        shutil.rmtree(stage, ignore_errors=True)
        raise
    result["html"] = str(out / "index.html") if html else None
    result["out"] = str(out)
    result["failed"] = [k for k, v in how.items() if v == "failed"]
    return result
